// The corner graph (corner_calibration.hpp says what it holds), built piece by
// piece: one function per kind of variable and factor, so that a new kind is
// one more function and a change to one kind is made in one place.
//
// Extension points, for quantities estimated beyond the cameras, the mount
// and the intrinsics:
//   - boardPoseSeen(o, j) is THE place where "the board pose that camera c
//     sees in the image of observation o, at instant j" is formed. Today it
//     is instant j's board pose variable. A camera's time offset moves it:
//     return the offset's key (and what the factor needs to move L_j, e.g.
//     the board's velocity at the stamp) there, and makeCornerFactor builds
//     the factor that applies it; nothing else changes.
//   - addKinematicFactor(j) builds the kinematic factor of instant j from its
//     first observation (FK, encoder covariance). Joint zero offsets replace
//     that factor by one that re-evaluates the chain at q + o.
//   - addCamera / addMount / addIntrinsics / addInstant add the variables (and
//     their priors); a new variable kind gets its own add function, called
//     from buildGraph (corner_calibration.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/offset_estimation.hpp"
#include "fgcal/core/factor_graph.hpp"
#include "fgcal/core/values.hpp"

namespace fgcal::apps::corners {

inline Key cameraKey(std::size_t c) { return key('c', c); }
inline Key boardKey(std::size_t j) { return key('b', j); }
inline Key intrinsicsKey(std::size_t c) { return key('k', c); }
inline constexpr Key kMountKey = key('m', 0);

/// One corner factor of the graph: its index there, the observation (index
/// into CalibrationProblemInput::observations) and the corner (index into
/// that observation's ImageCorners).
struct CornerRef {
  std::size_t factor, observation, corner;
};

struct CornerGraph {
  FactorGraph graph;
  Values values;
  std::vector<Key> fixed;                        ///< held constant (the mount when fixed)
  std::vector<std::vector<std::size_t>> groups;  ///< observations per instant j
  std::vector<std::size_t> kinematic;            ///< factor index of instant j's kinematic factor
  std::vector<CornerRef> corners;                ///< every corner factor, in graph order
  /// With backlash: the lag coefficients of the kinematic factors (the play
  /// operator with the previous solve's play, offset_graph.hpp).
  std::shared_ptr<const BacklashLag> backlash_lag;
};

/// The board pose a camera sees in one image: the variable(s) the corner
/// factor of that image reads for it. With time offsets the camera sees L_j
/// moved along the joint log from the instant's stamp to its image's exposure
/// (TimeOffsetFactor, through the mount, the camera's time offset and the
/// joint offsets when estimated).
struct SeenBoardPose {
  Key board;  ///< instant j's board pose L_j
  std::int64_t instant_ns = 0;  ///< the stamp L_j belongs to
  std::int64_t image_ns = 0;    ///< the image's stamp
};

class CornerGraphBuilder {
 public:
  /// `input` must match `problem` (checked by solveCornerCalibration).
  CornerGraphBuilder(const CalibrationProblemInput& problem, const CornerProblemInput& input);

  /// Camera c's pose variable.
  void addCamera(std::size_t c, const SE3& initial);
  /// Camera c's intrinsics variable, with its prior centred on the camera
  /// model's own intrinsics (CornerCamera::intrinsics_sigma).
  void addIntrinsics(std::size_t c, const VecX& initial);
  /// The mount variable: with its prior (the input's mount_prior and
  /// sigmas), or held constant at `initial` when `fixed`.
  void addMount(const SE3& initial, bool fixed);
  /// The time offsets of `cams` and the joint offsets, as
  /// CalibrationProblemInput::offsets asks (none: nothing), with their priors;
  /// values from `previous` where it has them, and with backlash the lag its
  /// play gives (offset_graph.hpp). Before addInstant.
  void addOffsets(const std::vector<std::size_t>& cams, const Values* previous);
  /// Instant j: its board pose variable and its kinematic factor; the
  /// instant's observations (the first gives its kinematics).
  void addInstant(std::size_t j, const std::vector<std::size_t>& observations, const SE3& initial);
  /// The board pose that observation o's camera sees at instant j.
  SeenBoardPose boardPoseSeen(std::size_t o, std::size_t j) const;
  /// One corner factor per corner k of observation o with keep[k] set,
  /// with `kernel` (null: plain least squares).
  void addCornerFactors(std::size_t o, std::size_t j, const std::vector<char>& keep,
                        const RobustKernel::Ptr& kernel);

  CornerGraph& graph() { return g_; }

 private:
  void addKinematicFactor(std::size_t j);
  Factor::Ptr makeCornerFactor(std::size_t c, const SeenBoardPose& seen, const Vec3& board_point,
                               const Eigen::Vector2d& pixel, const NoiseModel::Ptr& noise,
                               const RobustKernel::Ptr& kernel) const;
  /// The corner noise of observation o's image (at instant j, whose board
  /// pose and camera are already in the graph's values): the camera's
  /// pixel_sigma, or the image's own corner scatter about its best pose when
  /// that is larger (the PnP covariance's rule, SigmaSource::Larger), its
  /// far-off corners left out. The stated sigma alone when the camera's
  /// intrinsics are estimated.
  NoiseModel::Ptr imageNoise(std::size_t o, std::size_t j) const;

  const CalibrationProblemInput& problem_;
  const CornerProblemInput& input_;
  std::vector<std::shared_ptr<const vision::CameraModel>> models_;  // shared by a camera's factors
  std::vector<NoiseModel::Ptr> pixel_noise_;                         // per camera
  std::vector<char> intrinsics_added_;                               // per camera
  CornerGraph g_;
};

}  // namespace fgcal::apps::corners
