// The corner graph's builder (corner_graph.hpp).
#include "corner_graph.hpp"

#include "fgcal/factors/corner_factor.hpp"
#include "fgcal/factors/intrinsics_prior_factor.hpp"
#include "fgcal/factors/prior_factor.hpp"
#include "graph_parts.hpp"
#include "offset_graph.hpp"

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
  g_.graph.add(offsets::kinematicFactor(problem_.offsets, boardKey(j), kMountKey, first.T_base_link,
                                        first.joint_positions, detail::kinematicNoise(first, problem_)));
}

SeenBoardPose CornerGraphBuilder::boardPoseSeen(std::size_t o, std::size_t j) const {
  return {boardKey(j), problem_.observations[g_.groups[j].front()].stamp_ns, problem_.observations[o].stamp_ns};
}

Factor::Ptr CornerGraphBuilder::makeCornerFactor(std::size_t c, const SeenBoardPose& seen, const Vec3& board_point,
                                                 const Eigen::Vector2d& pixel, const RobustKernel::Ptr& kernel) const {
  // The corner as seen on the board pose (position 1 of its keys); with time
  // offsets, that pose moved to the image's exposure (offset_graph.hpp).
  Factor::Ptr corner =
      intrinsics_added_[c]
          ? std::make_shared<CornerFactor>(cameraKey(c), seen.board, intrinsicsKey(c), models_[c], board_point, pixel,
                                           pixel_noise_[c])
          : std::make_shared<CornerFactor>(cameraKey(c), seen.board, models_[c], board_point, pixel, pixel_noise_[c]);
  return offsets::imageFactor(problem_.offsets, std::move(corner), 1, kMountKey, c, seen.instant_ns, seen.image_ns,
                              kernel);
}

void CornerGraphBuilder::addCornerFactors(std::size_t o, std::size_t j, const std::vector<char>& keep,
                                          const RobustKernel::Ptr& kernel) {
  const auto c = static_cast<std::size_t>(problem_.observations[o].camera);
  const ImageCorners& im = input_.corners[o];
  const SeenBoardPose seen = boardPoseSeen(o, j);
  for (std::size_t k = 0; k < im.pixels.size(); ++k) {
    if (!keep[k]) continue;
    g_.corners.push_back({g_.graph.size(), o, k});
    g_.graph.add(makeCornerFactor(c, seen, im.board_points[k], im.pixels[k], kernel));
  }
}

}  // namespace fgcal::apps::corners
