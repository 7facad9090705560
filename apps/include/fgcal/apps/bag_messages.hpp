// The sensor_msgs a robot bag holds, turned into what the calibration uses:
// images into grey cv::Mats for detection (and into the pixels a dataset
// folder stores), CameraInfo into a camera's intrinsics, and a topic's
// JointState messages into a JointLog (joints.csv's table).
//
// Every check returns what was wrong as text (empty when fine) so that the
// caller names the bag, the topic and the message in its InputError.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/logs/messages.hpp"
#include "fgcal/vision/image_header.hpp"

namespace fgcal::apps {

/// The Image encodings read: mono8, mono16, rgb8, bgr8, rgba8, bgra8 and the
/// 8-bit Bayer mosaics bayer_rggb8, bayer_bggr8, bayer_gbrg8, bayer_grbg8.
const std::vector<std::string>& supportedImageEncodings();

/// Why `image` cannot be read (an encoding not in supportedImageEncodings(),
/// a step shorter than a row, data shorter than step x height), or empty.
std::string imageProblem(const logs::Image& image);

/// The image as 8-bit grey for detection (imageProblem must be empty):
/// mono16 keeps its high byte (as a 16-bit PNG read as grey does), colour is
/// converted as OpenCV converts BGR to grey, a Bayer mosaic is demosaiced by
/// OpenCV (to BGR, then to grey, so that an imported PNG reads the same).
cv::Mat imageToGray(const logs::Image& image);

/// The image as the dataset folder stores it (imageProblem must be empty), a
/// cv::Mat for cv::imwrite to PNG: mono8 and mono16 unchanged (the PNG's
/// decoded rows are the message's rows, big-endian mono16 included), colour
/// in OpenCV's BGR(A) order so that the PNG shows the right colours (its
/// decoded RGB rows are the rgb8/rgba8 message's rows), a Bayer mosaic
/// demosaiced to BGR (the folder format has no field for a mosaic's pattern).
cv::Mat imageForPng(const logs::Image& image);

/// The container of a CompressedImage from its format string: "jpeg" or
/// "png", or empty when it is neither (compressedDepth, tiff, ...). Accepts
/// the forms image_transport writes: "jpeg", "png", "mono8; jpeg compressed "
/// (trailing space), "bgr8; jpeg compressed bgr8", "rgb8; png compressed".
std::string compressedImageFormat(const std::string& format);

/// The compressed image decoded to 8-bit grey (cv::imdecode, as cv::imread
/// reads the imported file); empty when the bytes cannot be decoded. The
/// size is read from the PNG/JPEG header first: when it is not `expected`
/// (or, expected unknown, over vision::kMaxUncheckedPixels) the image is not
/// decoded and vision::ImageSizeMismatch is thrown with the header's size.
cv::Mat compressedToGray(const logs::CompressedImage& image, vision::ExpectedSize expected = {});

/// Fills `camera`'s distortion_model, intrinsics, distortion_coeffs and
/// resolution from a CameraInfo: plumb_bob (D = k1 k2 p1 p2 [k3]) and
/// rational_polynomial (k1 k2 p1 p2 k3 k4 k5 k6) as radtan when the terms
/// beyond p2 are zero, equidistant (k1..k4). Returns what was wrong (K with
/// skew or fx <= 0, a model or coefficient fgcal cannot take, binning, zero
/// size) or empty.
std::string intrinsicsFromCameraInfo(const logs::CameraInfo& info, CameraConfig* camera);

/// True when two CameraInfos give the same intrinsics (K, D, model, size).
bool sameIntrinsics(const logs::CameraInfo& a, const logs::CameraInfo& b);

/// Builds joints.csv's table from a topic's JointState messages in any order.
///
/// Samples are sorted by header stamp (never by record time). Messages with
/// the same stamp make one sample; where two of them carry the same joint,
/// the one recorded later (larger storage index) wins. A joint absent from a
/// sample keeps its value of the sample before (NaN until it first appears).
/// A NaN or inf position is stored as NaN, so the frames that need it are
/// skipped later. Columns are the joints in order of first appearance, or
/// only those asked for: a long recording holds hundreds of thousands of
/// messages, and a calibration needs the joints of one leg.
class JointStateCollector {
 public:
  /// `keep`: the joints whose positions are kept, in this order; empty:
  /// every joint.
  explicit JointStateCollector(std::vector<std::string> keep = {});
  /// Returns what was wrong with the message (positions neither empty nor
  /// one per name, a name given twice), or empty when it was taken. A message
  /// with no positions (efforts only) is counted and ignored.
  std::string add(const logs::JointState& message, std::uint64_t storage_index);
  std::size_t messages() const { return samples_.size(); }
  /// Messages that had no positions.
  std::size_t withoutPositions() const { return without_positions_; }
  /// The table; `duplicates` receives the number of messages merged into
  /// another of the same stamp. With `keep`: its joints that were seen, and
  /// every joint seen in JointLog::source_names.
  JointLog finish(std::size_t* duplicates = nullptr) const;

 private:
  struct Sample {
    std::int64_t stamp_ns = 0;
    std::uint64_t index = 0;
    std::uint32_t begin = 0;  ///< its kept positions: columns_/positions_ from here to the next sample's begin
  };
  std::vector<std::string> keep_;
  std::vector<std::string> names_;        ///< every joint seen, in order of first appearance
  std::map<std::string, int> column_of_;  ///< name -> index in names_
  std::vector<int> kept_column_;          ///< per joint of names_: its column in the table, -1 when not kept
  std::vector<Sample> samples_;
  std::vector<std::uint32_t> columns_;  ///< table column of each kept position
  std::vector<double> positions_;
  std::vector<int> scratch_;  ///< the joints of the message being added
  std::size_t without_positions_ = 0;
};

}  // namespace fgcal::apps
