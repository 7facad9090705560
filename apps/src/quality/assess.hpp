// The quality checks of a finished calibration (docs/outputs.md, "quality"):
// each compares a statistic of the graph at its solution with the
// distribution it has when the inputs are right, and flags it beyond a fixed
// false-alarm rate (kFalseAlarm); the diagnoses then try the alternatives
// that would explain a flagged statistic (hypotheses.hpp) and name the input
// whose change explains it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "fgcal/apps/calibrate_options.hpp"
#include "fgcal/apps/calibration_problem.hpp"
#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/quality.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal/kinematics/chain.hpp"
#include "fgcal/vision/camera_model.hpp"

namespace fgcal::apps::quality {

/// The false-alarm rate of every test on correct data: chi-square tail
/// probabilities below it are flagged. With about ten tests per run, a
/// correct run is flagged by one of them at most 1 % of the time.
inline constexpr double kFalseAlarm = 1e-3;

/// What the checks read of a run.
struct Context {
  const CalibrationProblemInput& problem;
  const CalibrationSolution& sol;
  const RigConfig& rig;
  const kinematics::KinematicChain& chain;
  const VecX& sigma_q;  ///< encoder sigma per chain joint
  const JointLog& joints;  ///< the chain's joints as logged
  const std::vector<vision::CameraModel>& models;
  /// How joint columns are named in fields: "joints.csv" for a folder, the
  /// joint-state topic for a bag ("joints.csv:COLUMN", "/joint_states:NAME").
  std::string joints_input = "joints.csv";
  Method method = Method::Pnp;
  EstimateSet estimate;
  /// The command as run (dataset, --rig, -o ...), to which a suggested
  /// option is appended when a finding's fix is one of ours.
  std::string command;
};

/// One factor family's chi-square at the solution and its degrees of
/// freedom (its share of the graph's redundancy).
struct FamilyStat {
  double chi2 = 0.0;
  double dof = 0.0;
  int factors = 0;
  double ratio() const { return dof > 0.0 ? chi2 / dof : 0.0; }
  /// P(chi-square(dof) > chi2): small when the family fits worse than its noise says.
  double pHigh() const;
  /// P(chi-square(dof) < chi2): small when it fits better than its noise says.
  double pLow() const;
};
struct Families {
  std::vector<FamilyStat> fiducial;  ///< per camera: its images' factors (PnP poses, or corners)
  FamilyStat kinematic;              ///< every instant's kinematic factor
};
/// The families' chi-square and redundancy: each instant's board pose
/// shares its 6 degrees of freedom among its factors by their leverage
/// (tr(Lambda_f (sum Lambda)^-1)); each camera takes 6 from its images, the
/// mount what its prior does not hold from the kinematics.
Families familyStatistics(const Context& ctx);

/// The joint log against the URDF's limits (joint_units or joint_limits,
/// unusable), or nothing when every reading is within them; needs no solution.
std::optional<Finding> jointLimitFinding(const kinematics::KinematicChain& chain, const VecX& sigma_q,
                                         const JointLog& joints, const std::string& joints_input);

/// One camera's corners about their own PnP poses at pixel_sigma: their
/// chi-square with its 2n - 6 degrees of freedom per image, and the
/// chi-square a radial pattern (a rho + b rho^3) explains, chi-square(2) on
/// a lens the camera model fits. `used`, when given, leaves out the images
/// it marks 0.
struct CornerScatter {
  double chi2 = 0.0, dof = 0.0, radial = 0.0;
};
CornerScatter cornerScatter(const CalibrationProblemInput& problem, const vision::CameraModel& model,
                            double pixel_sigma, int camera, const std::vector<char>* used = nullptr);

/// `in` with camera < 0: every PnP translation divided by k (the board k
/// times smaller than rig.yaml says); with a camera: only the depth (z) of
/// its PnP translations (its focal length k times larger than the lens's).
CalibrationProblemInput scaled(const CalibrationProblemInput& in, double k, int camera);
/// One PnP translation as scaled() changes it: divided by k, or only its
/// depth when `depth_only`.
Vec3 scaledTranslation(const Vec3& t, double k, bool depth_only);

struct Assessment {
  Quality quality;
  /// Per camera, the factor its covariance is multiplied by to cover what
  /// the model did not explain: the largest variance factor (chi-square /
  /// dof) of the flagged families that bear on it; 1 when none is flagged.
  std::vector<double> inflation;
  Families families;
};

/// Every check and diagnosis of docs/outputs.md; the solution's own findings
/// (too few instants, outlier rate, ...) come first.
Assessment assess(const Context& ctx);

}  // namespace fgcal::apps::quality
