// An image factor whose board is the board at the image's exposure time,
// when each camera's time offset (and, for a rolling shutter, its readout) is
// estimated or known.
//
// Time offset delta_c of camera c: an image stamped t was exposed at
// t + delta_c. Images of several cameras within the sync tolerance share one
// board pose variable L_j, the board (in the base frame) at the instant's
// stamp t_j, tied to the kinematics there by the kinematic factor. The board
// that camera c saw in its image stamped t_i is the board at t_i + delta_c:
//
//   P = L_j · D,   D = (F(t_j) M)^-1 · F(t_e) M,   F(t) = FK(q(t) + o)
//
// at the exposure t_e = t_i + delta_c + r R_c. A rolling shutter exposes the
// image's rows one after another: row v starts r R_c after the first, with
// r = v / (H - 1) its place in the readout and R_c the readout (first row to
// last). A corner factor gives its corner's row; an image-level factor (PnP)
// a row standing for the whole image, e.g. its corners' mean (an
// approximation: the pose fitted to a skewed image is not the board at any
// one time). r = 0, or R_c = 0, is a global shutter. delta_c and R_c are each
// either a variable or a constant.
//
// with M = T_link_marker the mount, q(t) a JointTrajectory (a smooth fit of
// the joint log) and o the joint zero offsets (zero when not estimated). D is
// the board's own motion from t_j to the exposure, read from the joint log
// through the kinematics and expressed in the board frame. Since L_j carries
// the encoder noise at t_j through the kinematic factor, the joint log's noise
// is counted once; D adds the error of the trajectory's change over
// |t_e - t_j|, which no covariance here accounts for: give a
// trajectory smooth enough that this error is small against the image's
// noise (a fit that follows the encoder noise makes cameras that share an
// instant disagree by it). D is exact, not the first-order L_j Exp(V delta_c)
// (V the board's body velocity at t_j), at the cost of a second forward
// kinematics: with a 15 ms delay on a moving leg the first-order board is
// off by 0.1-0.4 mm at its corners, a camera's whole error budget.
//
// This factor wraps an image factor on (..., board, ...) — a PnP relative
// pose or a corner reprojection — and hands it P in place of L_j. Its keys are
// the wrapped factor's keys (the board's key, now L_j, where it was), then M,
// and those of delta_c, R_c (VecX of size 1, seconds) and o (VecX, chain
// order) that are variables, in that order. Jacobians by the chain rule,
// right perturbations, [w v]:
//   dP / dL_j     = Ad(D^-1)
//   dP / dM       = I - Ad(D^-1)
//   dP / ddelta_c = J_M(q_b + o) qdot(t_e)          the board's body velocity at the exposure
//   dP / dR_c     = r dP / ddelta_c
//   dP / do       = J_M(q_b + o) - Ad(D^-1) J_M(q_a + o)
// where q_a = q(t_j), q_b = q(t_e) and J_M = Ad(M^-1) J is the
// chain's Jacobian expressed at the board (KinematicChain::forward with
// T_tip_marker = M): FK(q + d) M = FK(q) M Exp(J_M d).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "fgcal/core/factor.hpp"
#include "fgcal/factors/joint_trajectory.hpp"
#include "fgcal/kinematics/chain.hpp"

namespace fgcal {

class TimeOffsetFactor final : public Factor {
 public:
  /// Where the image lies in time, in seconds on the trajectory's clock.
  struct Timing {
    double instant = 0.0;  ///< t_j, the stamp at which the board pose variable is defined
    double image = 0.0;    ///< t_i, the image's stamp
    /// r, the row's place in the readout, v / (H - 1) in [0, 1]: 0 for the
    /// first row, 1 for the last.
    double row = 0.0;
    double time_offset = 0.0;  ///< delta_c (s) used when Variables::time_offset is absent
    double readout = 0.0;      ///< R_c (s) used when Variables::readout is absent
  };

  /// The variables besides the wrapped factor's: the mount (required), and
  /// those of the time offset, the readout and the joint offsets that are
  /// estimated; each absent one is a constant (Timing) or zero.
  struct Variables {
    Key mount = 0;  ///< T_link_marker (SE3)
    std::optional<Key> time_offset;    ///< absent: Timing::time_offset
    std::optional<Key> readout;        ///< absent: Timing::readout
    std::optional<Key> joint_offsets;  ///< absent: zero
  };

  /// `image_factor`: the wrapped factor; its key at `board_position` is the
  /// board pose (an SE3 variable). Its noise model is this factor's; give the
  /// robust kernel here (the wrapped factor's own is not applied). Throws
  /// std::invalid_argument for a missing factor, chain or trajectory, a
  /// board_position out of range, a trajectory whose size is not the chain's,
  /// a row outside [0, 1], a constant time offset or readout that is not
  /// finite, or a key of `variables` the wrapped factor already has.
  TimeOffsetFactor(Factor::Ptr image_factor, std::size_t board_position, const Variables& variables,
                   std::shared_ptr<const kinematics::KinematicChain> chain,
                   std::shared_ptr<const JointTrajectory> trajectory, Timing timing,
                   RobustKernel::Ptr robust = nullptr);
  /// A global shutter with an estimated time offset.
  TimeOffsetFactor(Factor::Ptr image_factor, std::size_t board_position, Key mount, Key time_offset,
                   std::optional<Key> joint_offsets, std::shared_ptr<const kinematics::KinematicChain> chain,
                   std::shared_ptr<const JointTrajectory> trajectory, Timing timing,
                   RobustKernel::Ptr robust = nullptr);

  void evaluate(const Variable* const* vars, double* residual, double* const* jacobians) const override;
  std::string describe() const override;

  /// The board at the exposure, P = L · D, at the given time offset, readout
  /// and o (empty: zero), whether those are variables or constants here. The
  /// overload without a readout uses Timing::readout. For reports and tests.
  SE3 boardAtExposure(const SE3& L, const SE3& M, double time_offset, const VecX& o = VecX()) const;
  SE3 boardAtExposure(const SE3& L, const SE3& M, double time_offset, double readout, const VecX& o) const;

  const Factor& imageFactor() const { return *inner_; }
  const Timing& timing() const { return timing_; }

  /// The most keys a wrapped factor may have.
  static constexpr std::size_t kMaxImageKeys = 8;

 private:
  Factor::Ptr inner_;
  std::size_t board_;
  // Positions in keys() of the variables; -1 when a constant (or zero) serves.
  int time_offset_ = -1, readout_ = -1, joint_offsets_ = -1;
  std::shared_ptr<const kinematics::KinematicChain> chain_;
  std::shared_ptr<const JointTrajectory> trajectory_;
  Timing timing_;
  VecX q_instant_;  // q(t_j), evaluated once
};

}  // namespace fgcal
