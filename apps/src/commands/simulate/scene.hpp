// The simulated scene (internal to the simulator): a seeded random source,
// the cameras and where they sit on the base, the board mount, and the test
// of whether a camera sees the board well. Placement is derived from the robot
// (sampled reachable workspace of the marker link), so any legged URDF works.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "fgcal/core/se3.hpp"
#include "fgcal/kinematics/chain.hpp"
#include "fgcal/vision/camera_model.hpp"
#include "fgcal/vision/charuco_target.hpp"

namespace fgcal::apps::sim {

/// Seeded random numbers with a fixed algorithm on every platform
/// (std::normal_distribution's is implementation-defined).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return (engine_() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double normal() {  // Box-Muller
    double u1 = uniform();
    while (u1 <= 0.0) u1 = uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  Vec3 unitVector() {
    Vec3 v(normal(), normal(), normal());
    while (v.norm() < 1e-9) v = Vec3(normal(), normal(), normal());
    return v.normalized();
  }
  std::size_t index(std::size_t n) { return static_cast<std::size_t>(uniform() * n) % n; }
  std::uint64_t next() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

/// SplitMix64: independent per-image seeds from (seed, camera, frame).
std::uint64_t mixSeed(std::uint64_t a, std::uint64_t b, std::uint64_t c);

struct SimCamera {
  std::string name;
  vision::CameraModel model;
  SE3 T_base_cam;
  /// Normalized image-plane bounds of the field of view (x/z, y/z), from the
  /// unprojected image border: guards against distortion folding far points.
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
};

/// The marker link's reachable workspace, sampled over the chain's joint limits.
struct Workspace {
  Vec3 hip;                    ///< first movable joint of the chain, base frame
  double reach = 0.0;          ///< largest hip-to-link distance seen
  Vec3 target;                 ///< centre of the raised-forward region
  VecX q_typical;              ///< a sample whose link sits near `target`
  std::vector<VecX> samples;   ///< joint samples (chain order)
  std::vector<SE3> T_base_link;  ///< their forward kinematics
};

/// Uniform joint samples within limits (continuous joints: [-pi, pi]).
VecX sampleJoints(const kinematics::KinematicChain& chain, Rng& rng);
/// Joint ranges used for sampling (limits, or [-pi, pi] when unlimited).
void jointRanges(const kinematics::KinematicChain& chain, VecX* lower, VecX* upper);

Workspace sampleWorkspace(const kinematics::KinematicChain& chain, const SE3& T_base_hip, Rng& rng,
                          int n_samples);

/// The names of the first `count` cameras (1..4), rig.yaml order.
std::vector<std::string> cameraNames(int count);

/// The cameras (1..4) for a distortion model name, placed from the workspace.
/// `width` x `height` > 0 replaces every camera's image size (focal length
/// scaled so that the field of view is at least the camera's own); `fov_deg`
/// > 0 then sets the horizontal field of view (withFieldOfView).
std::vector<SimCamera> makeCameras(int count, const std::string& distortion, const Workspace& ws, int width = 0,
                                   int height = 0, double fov_deg = 0.0);

/// The model with fx (and fy, keeping fy / fx) chosen so that a ray at
/// fov_deg / 2 from the optical axis projects at half the image width from
/// the principal point, through the distortion.
vision::CameraModel withFieldOfView(const vision::CameraModel& model, double fov_deg);

/// "" when every pixel of the image has one viewing ray in front of the
/// camera, found again by projecting it, with the angle from the optical axis
/// growing from the principal point to the image border (the distortion does
/// not fold inside the image); otherwise what fails, and where.
std::string projectionFolds(const vision::CameraModel& model);

/// The true board mount: at the typical raised pose the board centre sits
/// just in front of the link origin and the board faces the cameras.
SE3 designMount(const Workspace& ws, const kinematics::KinematicChain& chain,
                const std::vector<SimCamera>& cameras, const vision::CharucoTarget& target);

struct ViewQuality {
  bool in_image = false;  ///< all four board corners in front and inside the image
  double distance = 0.0;  ///< camera to board centre, metres
  double angle = 0.0;     ///< board normal vs viewing ray, radians
  bool good(double min_d = 0.3, double max_d = 0.9, double max_angle = 55.0 * M_PI / 180.0) const {
    return in_image && distance >= min_d && distance <= max_d && angle <= max_angle;
  }
};
ViewQuality viewQuality(const SimCamera& camera, const SE3& T_base_marker,
                        const vision::CharucoTarget& target, double margin_px = 8.0);

}  // namespace fgcal::apps::sim
