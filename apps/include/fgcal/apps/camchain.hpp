// Kalibr's camera chain (camchain.yaml), written by `fgcal calibrate
// --kalibr-out` and read by `fgcal evaluate`.
//
// Format (Kalibr's kalibr_common/ConfigReader.py, CameraChainParameters): top
// level keys cam0, cam1, ... and nothing else (Kalibr counts the cameras as
// the number of top-level keys); per camera camera_model, intrinsics
// [fu fv pu pv], distortion_model, distortion_coeffs, resolution [w h],
// rostopic when known, and for every camera after the first T_cn_cnm1: the
// 4x4 transform that maps points of camera n-1 into camera n,
// p_cn = T_cn_cnm1 p_cnm1, i.e. T_cn_cnm1 = T_base_cn^-1 T_base_cnm1 in
// fgcal's notation. fgcal adds `fgcal_camera: NAME` per camera (Kalibr reads
// cameras by key and ignores it) so that evaluate can match ground truth.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fgcal/apps/evaluate.hpp"
#include "fgcal/core/se3.hpp"

namespace fgcal::apps {

struct CamchainCamera {
  std::string name;  ///< fgcal's camera name (fgcal_camera); "camN" when a file has none
  std::string camera_model = "pinhole";
  std::array<double, 4> intrinsics{};  ///< fu, fv, pu, pv
  std::string distortion_model = "none";
  std::vector<double> distortion_coeffs;
  std::array<int, 2> resolution{};
  std::string rostopic;  ///< empty: not written
  /// Pose of this camera in cam0: T_cam0_camn (identity for cam0). The file
  /// stores the consecutive T_cn_cnm1; this is their composition.
  SE3 T_cam0_cam;
};

/// camchain.yaml text for cameras in chain order (cam0 first).
std::string formatKalibrCamchain(const std::vector<CamchainCamera>& cameras);

/// Reads a camchain (Kalibr's own files too: unknown per-camera keys such as
/// T_cam_imu, cam_overlaps or flip_camera are ignored). Throws InputError
/// naming the file and the key (cam1.T_cn_cnm1, ...) for a missing or invalid
/// field, a gap in cam0..camN, or a key that is not a camera.
std::vector<CamchainCamera> parseKalibrCamchain(const std::string& yaml_text, const std::string& source_name);
std::vector<CamchainCamera> loadKalibrCamchain(const std::string& path);

/// True when the text is YAML whose top-level keys are cam0, cam1, ... (a
/// camchain rather than a calibration.yaml).
bool looksLikeKalibrCamchain(const std::string& yaml_text);

/// The relative poses a camchain can be checked on: T_a_b for every pair of
/// its cameras (a before b in chain order) that ground truth also holds,
/// against T_base_a^-1 T_base_b of the truth. Errors are in camera a's frame;
/// NEES is NaN (a camchain has no covariance). Throws InputError when fewer
/// than two cameras are in both.
struct RelativeEvaluation {
  std::vector<std::pair<std::string, PoseError>> pairs;  ///< "T_a_b" -> error
  std::vector<std::string> unmatched;                    ///< camchain cameras without ground truth
};
RelativeEvaluation evaluateCamchain(const std::vector<CamchainCamera>& cameras, const GroundTruth& truth,
                                    const std::string& camchain_path);
std::string formatRelativeEvaluationTable(const RelativeEvaluation& eval);

}  // namespace fgcal::apps
