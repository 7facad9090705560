// Every cv::aruco call of fgcal, written against OpenCV 4.6's contrib aruco
// module. See aruco_adapter.hpp for why this is one file.
#include "aruco_adapter.hpp"

#include <sstream>

#include <opencv2/aruco.hpp>
#include <opencv2/aruco/charuco.hpp>

#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision::detail {

struct ArucoBoard {
  cv::Ptr<cv::aruco::Dictionary> dictionary;
  cv::Ptr<cv::aruco::CharucoBoard> board;
  cv::Ptr<cv::aruco::DetectorParameters> params;
};

namespace {
struct DictEntry {
  const char* name;
  cv::aruco::PREDEFINED_DICTIONARY_NAME id;
  int size;
};
#define FGCAL_DICT(n, s) {#n, cv::aruco::n, s}
const DictEntry kDictionaries[] = {
    FGCAL_DICT(DICT_4X4_50, 50),           FGCAL_DICT(DICT_4X4_100, 100),
    FGCAL_DICT(DICT_4X4_250, 250),         FGCAL_DICT(DICT_4X4_1000, 1000),
    FGCAL_DICT(DICT_5X5_50, 50),           FGCAL_DICT(DICT_5X5_100, 100),
    FGCAL_DICT(DICT_5X5_250, 250),         FGCAL_DICT(DICT_5X5_1000, 1000),
    FGCAL_DICT(DICT_6X6_50, 50),           FGCAL_DICT(DICT_6X6_100, 100),
    FGCAL_DICT(DICT_6X6_250, 250),         FGCAL_DICT(DICT_6X6_1000, 1000),
    FGCAL_DICT(DICT_7X7_50, 50),           FGCAL_DICT(DICT_7X7_100, 100),
    FGCAL_DICT(DICT_7X7_250, 250),         FGCAL_DICT(DICT_7X7_1000, 1000),
    FGCAL_DICT(DICT_ARUCO_ORIGINAL, 1024), FGCAL_DICT(DICT_APRILTAG_16h5, 30),
    FGCAL_DICT(DICT_APRILTAG_25h9, 35),    FGCAL_DICT(DICT_APRILTAG_36h10, 2320),
    FGCAL_DICT(DICT_APRILTAG_36h11, 587),
};
#undef FGCAL_DICT

const DictEntry& findDictionary(const std::string& name) {
  for (const auto& e : kDictionaries)
    if (name == e.name) return e;
  std::ostringstream s;
  s << "target.dictionary: unknown dictionary '" << name << "'; expected one of:";
  for (const auto& e : kDictionaries) s << ' ' << e.name;
  throw VisionError(s.str());
}
}  // namespace

const std::vector<std::string>& predefinedDictionaryNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& e : kDictionaries) v.emplace_back(e.name);
    return v;
  }();
  return names;
}

int dictionarySize(const std::string& name) { return findDictionary(name).size; }

std::shared_ptr<const ArucoBoard> makeArucoBoard(const CharucoTarget& target) {
  const DictEntry& e = findDictionary(target.dictionary);
  auto b = std::make_shared<ArucoBoard>();
  b->dictionary = cv::aruco::getPredefinedDictionary(e.id);
  b->board = cv::aruco::CharucoBoard::create(target.squares_x, target.squares_y,
                                             static_cast<float>(target.square_size),
                                             static_cast<float>(target.marker_size), b->dictionary);
  b->params = cv::aruco::DetectorParameters::create();
  return b;
}

MarkerSet detectMarkers(const ArucoBoard& board, const cv::Mat& gray) {
  MarkerSet out;
  // detectMarkers writes into the parameters it is given in no version we
  // know, but it takes a non-const Ptr; a per-call copy keeps threads apart.
  cv::Ptr<cv::aruco::DetectorParameters> params =
      cv::makePtr<cv::aruco::DetectorParameters>(*board.params);
  cv::aruco::detectMarkers(gray, board.dictionary, out.corners, out.ids, params);
  return out;
}

void interpolateCorners(const ArucoBoard& board, const MarkerSet& markers, const cv::Mat& gray,
                        std::vector<cv::Point2f>* corners, std::vector<int>* ids) {
  corners->clear();
  ids->clear();
  if (markers.ids.empty()) return;
  cv::aruco::interpolateCornersCharuco(markers.corners, markers.ids, gray, board.board, *corners,
                                       *ids);
}

cv::Mat drawBoard(const ArucoBoard& board, cv::Size size, int margin) {
  cv::Mat img;
  board.board->draw(size, img, margin, 1);
  return img;
}

std::vector<std::vector<std::pair<int, int>>> nearestMarkerCorners(const ArucoBoard& board) {
  const auto& b = *board.board;
  std::vector<std::vector<std::pair<int, int>>> out(b.chessboardCorners.size());
  for (size_t c = 0; c < out.size() && c < b.nearestMarkerIdx.size(); ++c)
    for (size_t k = 0; k < b.nearestMarkerIdx[c].size(); ++k)
      out[c].emplace_back(b.ids[static_cast<size_t>(b.nearestMarkerIdx[c][k])],
                          b.nearestMarkerCorners[c][k]);
  return out;
}

std::vector<cv::Point3f> boardCorners(const ArucoBoard& board) {
  return board.board->chessboardCorners;
}

}  // namespace fgcal::vision::detail
