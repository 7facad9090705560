// Validation and geometry of the ChArUco target (board frame of OpenCV 4.6).
#include "fgcal/vision/charuco_target.hpp"

#include <sstream>

#include "aruco_adapter.hpp"
#include "fgcal/vision/vision_error.hpp"

namespace fgcal::vision {

void CharucoTarget::validate() const {
  if (squares_x < 2 || squares_y < 2)
    throw VisionError("target.squares_x / squares_y: expected at least 2 squares each, got " +
                      std::to_string(squares_x) + " x " + std::to_string(squares_y));
  if (!(square_size > 0.0))
    throw VisionError("target.square_size: expected a positive length in metres");
  if (!(marker_size > 0.0))
    throw VisionError("target.marker_size: expected a positive length in metres");
  if (!(marker_size < square_size))
    throw VisionError("target.marker_size: expected smaller than square_size (" +
                      std::to_string(marker_size) + " >= " + std::to_string(square_size) + ")");
  const int available = detail::dictionarySize(dictionary);  // throws on unknown names
  if (available < markerCount()) {
    std::ostringstream s;
    s << "target.dictionary: " << dictionary << " has " << available << " markers, the "
      << squares_x << "x" << squares_y << " board needs " << markerCount();
    throw VisionError(s.str());
  }
}

Vec3 CharucoTarget::cornerPosition(int id) const {
  if (id < 0 || id >= cornerCount())
    throw VisionError("ChArUco corner id " + std::to_string(id) + " out of range [0, " +
                      std::to_string(cornerCount()) + ")");
  const int per_row = squares_x - 1;
  return Vec3((id % per_row + 1) * square_size, (id / per_row + 1) * square_size, 0.0);
}

std::vector<Vec3> CharucoTarget::cornerPositions() const {
  std::vector<Vec3> out;
  out.reserve(static_cast<size_t>(std::max(0, cornerCount())));
  for (int i = 0; i < cornerCount(); ++i) out.push_back(cornerPosition(i));
  return out;
}

const std::vector<std::string>& dictionaryNames() { return detail::predefinedDictionaryNames(); }

std::vector<Vec3> openCvCornerPositions(const CharucoTarget& target) {
  target.validate();
  const auto board = detail::makeArucoBoard(target);
  std::vector<Vec3> out;
  for (const auto& p : detail::boardCorners(*board)) out.emplace_back(p.x, p.y, p.z);
  return out;
}

cv::Mat drawTarget(const CharucoTarget& target, int px_per_square, int margin_px) {
  target.validate();
  if (px_per_square < 8 || margin_px < 0)
    throw VisionError("drawTarget: expected px_per_square >= 8 and margin_px >= 0");
  const auto board = detail::makeArucoBoard(target);
  const cv::Size size(target.squares_x * px_per_square + 2 * margin_px,
                      target.squares_y * px_per_square + 2 * margin_px);
  return detail::drawBoard(*board, size, margin_px);
}

}  // namespace fgcal::vision
