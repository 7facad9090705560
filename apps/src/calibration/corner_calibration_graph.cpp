// The corner graph's builder (corner_calibration_graph.hpp).
#include "calibration/corner_calibration_graph.hpp"

#include "calibration/graph_parts.hpp"
#include "calibration/offset_graph.hpp"
#include "fgcal/factors/corner_factor.hpp"
#include "fgcal/factors/intrinsics_prior_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "fgcal/vision/pnp.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace fgcal::apps::corners {

CornerGraphBuilder::CornerGraphBuilder(const CalibrationProblemInput& problem, const CornerProblemInput& input)
    : problem_(problem), input_(input), intrinsics_added_(input.cameras.size(), 0) {
  for (const CornerCamera& cam : input.cameras) {
    models_.push_back(std::make_shared<const vision::CameraModel>(cam.model));
    pixel_noise_.push_back(NoiseModel::isotropic(2, cam.pixel_sigma));
  }
}

void CornerGraphBuilder::addCamera(std::size_t c, const SE3& initial) { g_.values.insert(cameraKey(c), initial); }

void CornerGraphBuilder::addIntrinsics(std::size_t c, const VecX& initial) {
  const CornerCamera& cam = input_.cameras[c];
  CornerFactor::insertIntrinsics(g_.values, intrinsicsKey(c), cam.model.withIntrinsics(initial));
  g_.graph.emplace<IntrinsicsPriorFactor>(intrinsicsKey(c), cam.model.intrinsicsVector(), cam.intrinsics_sigma);
  intrinsics_added_[c] = 1;
}

void CornerGraphBuilder::addMount(const SE3& initial, bool fixed) {
  g_.values.insert(kMountKey, initial);
  if (fixed)
    g_.fixed.push_back(kMountKey);
  else
    g_.graph.emplace<PriorFactorSE3>(kMountKey, problem_.mount_prior,
                                     detail::mountPriorNoise(problem_.mount_sigma_m, problem_.mount_sigma_rad));
}

void CornerGraphBuilder::addOffsets(const std::vector<std::size_t>& cams, const Values* previous) {
  offsets::addVariables(problem_.offsets, cams, previous, g_.graph, g_.values);
  g_.backlash_lag = offsets::backlashLag(problem_.offsets, previous);
}

void CornerGraphBuilder::addInstant(std::size_t j, const std::vector<std::size_t>& observations, const SE3& initial) {
  if (g_.groups.size() <= j) {
    g_.groups.resize(j + 1);
    g_.kinematic.resize(j + 1);
  }
  g_.groups[j] = observations;
  g_.values.insert(boardKey(j), initial);
  addKinematicFactor(j);
}

void CornerGraphBuilder::addKinematicFactor(std::size_t j) {
  const BoardObservation& first = problem_.observations[g_.groups[j].front()];
  g_.kinematic[j] = g_.graph.size();
  g_.graph.add(offsets::kinematicFactor(problem_.offsets, g_.backlash_lag.get(), boardKey(j), kMountKey,
                                        first.T_base_link, first.joint_positions, first.stamp_ns,
                                        detail::kinematicNoise(first, problem_)));
}

namespace {

// The corner scatter of one image about a pose, by the median residual so that
// a few bad corners (the gate's to reject) do not widen it: for isotropic
// noise of std s a residual's norm has median 1.1774 s, and the pose's fit
// takes 6 of the 2n degrees of freedom. Negative when a point is not in front.
double medianScatter(const vision::CameraModel& model, const SE3& T_cam_marker, const std::vector<Vec3>& points,
                     const std::vector<Eigen::Vector2d>& pixels, std::vector<double>* norms) {
  Eigen::VectorXd r;
  if (!vision::reprojection(model, T_cam_marker, points, pixels, &r, nullptr)) return -1.0;
  norms->resize(pixels.size());
  for (std::size_t k = 0; k < pixels.size(); ++k) (*norms)[k] = r.segment<2>(2 * static_cast<Eigen::Index>(k)).norm();
  std::vector<double> sorted = *norms;
  const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  const auto n2 = static_cast<double>(2 * pixels.size());
  return *mid / 1.1774 * std::sqrt(n2 / (n2 - 6.0));
}

}  // namespace

NoiseModel::Ptr CornerGraphBuilder::imageNoise(std::size_t o, std::size_t j) const {
  const BoardObservation& obs = problem_.observations[o];
  const auto c = static_cast<std::size_t>(obs.camera);
  const ImageCorners& im = input_.corners[o];
  const double stated = input_.cameras[c].pixel_sigma;
  // With the intrinsics estimated, the scatter about a PnP pose through the
  // prior intrinsics is their error as much as the detector's noise.
  if (intrinsics_added_[c] || im.pixels.size() < 6) return pixel_noise_[c];
  // Which corners are far off: by the residuals at the start of this solve
  // (camera and board pose from the solution so far, which the kinematics and
  // the other images hold), not about the image's own PnP pose, which a
  // least-squares fit lets far-off corners pull towards them.
  const SE3 T_cam_board = g_.values.at<SE3>(cameraKey(c)).inverse() * g_.values.at<SE3>(boardKey(j));
  std::vector<double> norms;
  const double s0 = medianScatter(*models_[c], T_cam_board, im.board_points, im.pixels, &norms);
  if (s0 < 0.0) return pixel_noise_[c];
  const double limit = 3.0 * std::max(s0, stated);
  std::vector<Vec3> points;
  std::vector<Eigen::Vector2d> pixels;
  for (std::size_t k = 0; k < norms.size(); ++k)
    if (norms[k] <= limit) {
      points.push_back(im.board_points[k]);
      pixels.push_back(im.pixels[k]);
    }
  if (pixels.size() < 6) return pixel_noise_[c];
  // The scatter of the rest about their own best pose: the detector's noise in
  // this image, apart from any disagreement with the other images (the
  // gate's to judge).
  SE3 pose;
  try {
    pose = vision::refinePose(*models_[c], obs.T_cam_marker, points, pixels).T_cam_marker;
  } catch (const std::exception&) {
    return pixel_noise_[c];
  }
  const double s = medianScatter(*models_[c], pose, points, pixels, &norms);
  return s > stated ? NoiseModel::isotropic(2, s) : pixel_noise_[c];
}

SeenBoardPose CornerGraphBuilder::boardPoseSeen(std::size_t o, std::size_t j) const {
  return {boardKey(j), problem_.observations[g_.groups[j].front()].stamp_ns, problem_.observations[o].stamp_ns};
}

Factor::Ptr CornerGraphBuilder::makeCornerFactor(std::size_t c, const SeenBoardPose& seen, const Vec3& board_point,
                                                 const Eigen::Vector2d& pixel, const NoiseModel::Ptr& noise,
                                                 const RobustKernel::Ptr& kernel) const {
  // The corner as seen on the board pose (position 1 of its keys); with time
  // offsets, that pose moved to the image's exposure (offset_graph.hpp).
  Factor::Ptr corner =
      intrinsics_added_[c]
          ? std::make_shared<CornerFactor>(cameraKey(c), seen.board, intrinsicsKey(c), models_[c], board_point, pixel,
                                           noise)
          : std::make_shared<CornerFactor>(cameraKey(c), seen.board, models_[c], board_point, pixel, noise);
  return offsets::imageFactor(problem_.offsets, std::move(corner), 1, kMountKey, c, seen.instant_ns, seen.image_ns,
                              problem_.offsets.rowFraction(c, pixel.y()), kernel);
}

void CornerGraphBuilder::addCornerFactors(std::size_t o, std::size_t j, const std::vector<char>& keep,
                                          const RobustKernel::Ptr& kernel) {
  const auto c = static_cast<std::size_t>(problem_.observations[o].camera);
  const ImageCorners& im = input_.corners[o];
  const SeenBoardPose seen = boardPoseSeen(o, j);
  const NoiseModel::Ptr noise = imageNoise(o, j);
  for (std::size_t k = 0; k < im.pixels.size(); ++k) {
    if (!keep[k]) continue;
    g_.corners.push_back({g_.graph.size(), o, k});
    g_.graph.add(makeCornerFactor(c, seen, im.board_points[k], im.pixels[k], noise, kernel));
  }
}

}  // namespace fgcal::apps::corners
