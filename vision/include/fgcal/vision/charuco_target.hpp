// The ChArUco calibration target, as rig.yaml's `target:` block describes it,
// and its geometry in OpenCV 4.6's board frame (docs/design.md, Conventions): origin at the
// top-left corner of the drawn board, x right, y down, z = 0 on the board;
// ChArUco corner ids row-major, corner 0 at (square, square, 0).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "fgcal/core/types.hpp"

namespace fgcal::vision {

struct CharucoTarget {
  int squares_x = 5;
  int squares_y = 7;
  double square_size = 0.04;  ///< metres
  double marker_size = 0.03;  ///< metres
  std::string dictionary = "DICT_4X4_50";  ///< OpenCV predefined dictionary name

  /// Throws VisionError naming the field: sizes > 0, marker_size <
  /// square_size, squares >= 2 in each direction, a known dictionary with
  /// enough markers for the board.
  void validate() const;

  /// Number of ChArUco (inner chessboard) corners: (squares_x-1)(squares_y-1).
  int cornerCount() const { return (squares_x - 1) * (squares_y - 1); }
  /// Number of markers on the board (the white squares).
  int markerCount() const { return (squares_x * squares_y) / 2; }
  /// Position of ChArUco corner `id` in the board frame (z = 0); throws
  /// VisionError on an id out of range.
  Vec3 cornerPosition(int id) const;
  /// All corner positions, index = corner id.
  std::vector<Vec3> cornerPositions() const;
};

/// Every OpenCV predefined dictionary name this build accepts, in OpenCV's order.
const std::vector<std::string>& dictionaryNames();

/// The chessboard corners as OpenCV's own CharucoBoard object holds them
/// (float precision); tests compare cornerPositions() with these.
std::vector<Vec3> openCvCornerPositions(const CharucoTarget& target);

/// OpenCV's drawing of the board (8-bit, 1 channel): `px_per_square` pixels
/// per square and a white margin of `margin_px` on every side, so board point
/// (X, Y) in metres sits at pixel-edge coordinate margin_px + X / square_size *
/// px_per_square (pixel centre coordinate minus 0.5).
cv::Mat drawTarget(const CharucoTarget& target, int px_per_square, int margin_px);

}  // namespace fgcal::vision
