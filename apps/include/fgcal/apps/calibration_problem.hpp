// The calibration as an estimation problem, independent of images and files:
// board poses seen by cameras (PnP, with their vertex-jitter covariance) and
// the forward kinematics at each image, in; camera poses in the base frame and
// the board mount, with honest covariances, out.
//
// Images taken within the sync tolerance share one board pose (the paper's
// F2); single_camera solves each camera on its own (F1). Each camera is
// initialized robustly from its own detections; gross outliers are handled by
// a robust kernel first, then removed by a chi-square gate, and the final
// solve is plain least squares so that the covariance is the Gaussian one.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/offset_estimation.hpp"
#include "fgcal/apps/quality.hpp"
#include "fgcal/core/optimizer.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

/// A 6x6 covariance kept as its 21 distinct entries (the upper triangle, by
/// columns): a long recording keeps two per image, 168 bytes each instead of
/// 288. Assigned from any 6x6 matrix (its upper triangle is kept), read back
/// as a Mat6 (matrix(), or where a Mat6 is expected).
class PackedCovariance6 {
 public:
  PackedCovariance6() = default;  // zero
  template <class Derived>
  PackedCovariance6(const Eigen::MatrixBase<Derived>& m) {  // NOLINT: implicit, as a Mat6 member was
    static_assert(Derived::RowsAtCompileTime == 6 && Derived::ColsAtCompileTime == 6, "a 6x6 matrix");
    std::size_t k = 0;
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r <= c; ++r) v_[k++] = m(r, c);
  }
  Mat6 matrix() const {
    Mat6 m;
    std::size_t k = 0;
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r <= c; ++r) m(r, c) = m(c, r) = v_[k++];
    return m;
  }
  operator Mat6() const { return matrix(); }  // NOLINT: implicit, as a Mat6 member was
  double operator()(int r, int c) const { return r <= c ? v_[static_cast<std::size_t>(c * (c + 1) / 2 + r)]
                                                        : v_[static_cast<std::size_t>(r * (r + 1) / 2 + c)]; }

 private:
  std::array<double, 21> v_{};
};

/// One image in which the board was found.
struct BoardObservation {
  int camera = 0;              // index into CalibrationProblemInput::camera_names
  std::int64_t stamp_ns = 0;
  SE3 T_cam_marker;            // PnP
  PackedCovariance6 covariance;       // of T_cam_marker's right perturbation, [w v]
  SE3 T_base_link;             // forward kinematics at this stamp
  PackedCovariance6 link_covariance;  // encoder noise through the leg Jacobian
  VecX joint_positions;        // the chain's joints at this stamp (degeneracy checks)
  /// Its detected corners: CalibrationProblemInput::corners from
  /// corners_begin, corners_count of them (none when the problem was made
  /// without corners).
  std::uint32_t corners_begin = 0, corners_count = 0;
};

/// The detected ChArUco corners of every observation, stored flat: a long
/// recording has tens of thousands of images of about 20 corners each. The
/// pixels are single precision, as the detector finds them (OpenCV's
/// corners are float: 6e-5 px apart at 1000 px), half the memory of double.
struct DetectedCorners {
  std::vector<Eigen::Vector2f> px;  // pixels, pixel-centre convention (vision::CameraModel::project's)
  std::vector<std::uint16_t> id;    // ChArUco corner id of each, same order
  std::vector<Vec3> board_points;   // indexed by corner id: its position in the board frame (NaN when never seen)

  /// Corner k's board point.
  const Vec3& boardPoint(std::size_t k) const { return board_points[id[k]]; }
  /// Corner k's pixel.
  Eigen::Vector2d pixel(std::size_t k) const { return px[k].cast<double>(); }
  /// Corners [begin, begin + count) appended as the board points and pixels PnP takes.
  void appendCorrespondences(std::size_t begin, std::size_t count, std::vector<Vec3>& points,
                             std::vector<Eigen::Vector2d>& pixels) const {
    for (std::size_t k = begin; k < begin + count; ++k) {
      points.push_back(boardPoint(k));
      pixels.push_back(pixel(k));
    }
  }
};

/// See CalibrationProblemInput::fiducial_covariance_scale.
inline constexpr double kDefaultFiducialCovarianceScale = 1.1;
/// Empty when `scale` is a valid fiducial_covariance_scale (finite, >= 1);
/// else what was expected and what was given, for the caller's error.
std::string fiducialCovarianceScaleProblem(double scale);

struct CalibrationProblemInput {
  std::vector<std::string> camera_names;
  std::vector<std::optional<SE3>> camera_guesses;  // same size; nullopt: initialize from detections
  std::vector<BoardObservation> observations;
  DetectedCorners corners;         // of the observations (BoardObservation::corners_begin); the pose factors do not use them
  SE3 mount_prior;                 // T_link_marker, e.g. from CAD
  double mount_sigma_m = 0.002;    // prior std of the mount; both zero: held fixed
  double mount_sigma_rad = 0.01;
  bool fix_mount = false;
  double sync_tolerance_ms = 1.0;
  /// A floor added to every kinematic covariance (std, metres and radians).
  /// Encoder noise alone leaves J Sigma_q J^T singular (a 3-joint leg moves
  /// the foot in 3 of 6 directions); real legs also carry unmodelled errors
  /// (link lengths, deflection, backlash) of this order.
  double kinematic_floor_m = 1e-4;
  double kinematic_floor_rad = 1e-4;
  /// Every image's PnP covariance is multiplied by this factor (>= 1) in the
  /// fiducial factors, and so in the gate and fiducial_chi2 (the gate at the
  /// 99.9 % point against the scaled covariance is the 99.99 % point against
  /// an image's own). The detection errors of one recording are not
  /// independent: consecutive views of the board differ little, and the
  /// detector's view-dependent error repeats over the next second or two of
  /// motion, so factors treated as independent count the same error again as
  /// new information. On rendered recordings at 0.5 px the cross-image terms
  /// added 19 % on average (1-51 %) to the variance of a camera's mean image
  /// error, while the kinematic floors and the mount prior keep the model
  /// about 5 % conservative; over 100 seeds 1.1 centres the mean NEES of
  /// every estimate (docs/studies/uncertainty.md). 1 treats every image as independent, as the paper does.
  double fiducial_covariance_scale = kDefaultFiducialCovarianceScale;
  bool single_camera = false;      // F1: every camera alone
  /// Camera time offsets and joint zero offsets estimated with the poses
  /// (offset_estimation.hpp); BoardObservation::joint_positions are then the
  /// encoder readings the kinematics are re-evaluated at.
  OffsetModel offsets;
};

struct RejectedObservation {
  std::size_t observation;  // index into the input's observations
  std::string reason;
};

struct CameraEstimate {
  std::string name;
  SE3 T_base_cam;
  Mat6 covariance;  // [w v], right perturbation of T_base_cam
  int observations_used = 0;
  SE3 initial_guess;
};

/// One board pose of the final solve: the images that share it, its estimate
/// and how well the kinematics agree with it (for reports).
struct InstantEstimate {
  std::int64_t stamp_ns = 0;               // of its first image
  std::vector<std::size_t> observations;   // indices into the input's observations
  SE3 T_base_marker;                       // estimated board pose
  double kinematic_chi2 = 0.0;             // |W r|^2 of its kinematic factor at the solution
};

struct CalibrationSolution {
  std::vector<CameraEstimate> cameras;
  SE3 T_link_marker;
  Mat6 mount_covariance = Mat6::Zero();
  bool mount_estimated = false;
  std::vector<RejectedObservation> rejected;
  std::vector<char> used;            // per input observation
  std::vector<double> fiducial_chi2; // per input observation: |W r|^2 of its factor (PnP covariance scaled) in the last solve that had it (NaN: never solved)
  int instants = 0;
  /// The robust solve(s) and the final one, for reports; their values hold
  /// the cameras and the mount (the board poses are in instant_estimates).
  std::vector<OptimizerResult> solves;
  std::vector<std::string> solve_labels;  // same size: e.g. "robust (cam0, cam1)", "final (cam0, cam1)"
  std::vector<InstantEstimate> instant_estimates;  // the final solve(s)' board poses
  std::vector<int> instant_of;       // per input observation: index into instant_estimates, -1 when not used
  /// Eigenvalues (ascending) of the mount's information (inverse marginal
  /// covariance) in units of (0.1 deg, 1 mm)^-2: below 1, some direction of
  /// the mount is known to worse than 0.1 deg / 1 mm. Zero when held fixed.
  Vec6 mount_information_eigenvalues = Vec6::Zero();
  /// The offsets of CalibrationProblemInput::offsets, when estimated.
  OffsetEstimates offsets;
  /// cov(xi_a, xi_b) of two cameras solved together (a < b, camera indices);
  /// cameras of different solves (F1, or no shared instant) are independent.
  struct CrossCovariance {
    std::size_t a = 0, b = 0;
    Mat6 cov = Mat6::Zero();
  };
  std::vector<CrossCovariance> camera_cross_covariances;
  std::vector<std::string> warnings;
  /// The solve's own findings (quality.hpp: too few instants, the outlier
  /// rate, what the data do not observe, ...); each message is also in warnings.
  std::vector<Finding> findings;
  /// False when the gate still rejected images after its last gated solve:
  /// the last solve is kept without a further gate, with a `convergence`
  /// check (the models do not explain the data).
  bool gate_settled = true;
};

/// Solves. Throws DataError (exit 1) when the data cannot support a
/// calibration: a camera with too few usable observations, too few instants,
/// degenerate motion, no convergence; InputError (exit 2) when an estimated
/// time offset moves a camera's images past the joint log.
CalibrationSolution solveCalibration(const CalibrationProblemInput& input);

/// The chi-square gate for one 6-dof fiducial factor (99.9 %).
constexpr double kFiducialGate = 22.4577;

/// Thresholds of the plain-words warnings of solveCalibration.
/// Fewer instants than this: the result rests on little data.
constexpr int kWarnMinInstants = 50;
/// The mount's smallest information eigenvalue (units of
/// CalibrationSolution::mount_information_eigenvalues) below this: the board
/// turned too little for the mount to be told from the cameras.
constexpr double kWarnMountInformation = 1.0;
/// More than this fraction of a camera's images rejected as outliers.
constexpr double kWarnOutlierRate = 0.10;

}  // namespace fgcal::apps
