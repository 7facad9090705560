# Cameras and the ChArUco board from Python: projection against the pinhole
# formula and central differences, unprojection round trips, detection on
# numpy images rendered at a known pose (gray and BGR), PnP with covariance
# against that pose, the real photos of the shared data, and the GIL
# released during detection.
import csv
import os

import numpy as np
import pytest

import fgcal
from conftest import runs_without_gil

TARGET = fgcal.CharucoTarget(5, 7, 0.04, 0.03, "DICT_4X4_50")


def camera(distortion="radtan"):
    coeffs = {"radtan": [-0.05, 0.02, 1e-4, -2e-4], "equidistant": [0.01, -0.005, 0.001, 0.0], "none": []}
    return fgcal.CameraModel([600.0, 605.0, 511.0, 270.0], [1024, 544], distortion, coeffs[distortion])


def board_pose(tilt_deg=20.0, distance=0.6):
    """The board's centre at `distance` in front of the camera, tilted about x and y."""
    R = fgcal.so3.from_rpy(np.radians(tilt_deg), np.radians(-0.5 * tilt_deg), 0.1)
    centre = np.array([0.5 * 5 * 0.04, 0.5 * 7 * 0.04, 0.0])
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.array([0.02, -0.01, distance]) - R @ centre
    return T


@pytest.mark.parametrize("distortion", ["none", "radtan", "equidistant"])
def test_project_unproject_and_jacobian(distortion):
    cam = camera(distortion)
    rng = np.random.default_rng(3)
    for _ in range(20):
        p = np.array([rng.uniform(-0.3, 0.3), rng.uniform(-0.2, 0.2), rng.uniform(0.5, 2.0)])
        uv, J = cam.project(p, jacobian=True)
        if distortion == "none":
            np.testing.assert_allclose(uv, [600 * p[0] / p[2] + 511, 605 * p[1] / p[2] + 270], atol=1e-9)
        h = 1e-6
        num = np.array([(cam.project(p + h * e) - cam.project(p - h * e)) / (2 * h) for e in np.eye(3)]).T
        np.testing.assert_allclose(J, num, atol=1e-4)
        b = cam.unproject(uv)
        np.testing.assert_allclose(b, p / np.linalg.norm(p), atol=1e-9)
    pts = np.array([[0.1, 0.0, 1.0], [0.0, 0.0, -1.0]])
    out = cam.project_points(pts)
    np.testing.assert_allclose(out[0], cam.project(pts[0]))
    assert np.all(np.isnan(out[1])) and cam.project(pts[1]) is None
    np.testing.assert_allclose(cam.K, [[600, 0, 511], [0, 605, 270], [0, 0, 1]])


def test_bad_camera_parameters_are_input_errors():
    with pytest.raises(fgcal.InputError, match="radtan"):
        fgcal.CameraModel([600, 600, 320, 240], [640, 480], "radtan", [0.1, 0.2, 0.3])
    with pytest.raises(fgcal.InputError, match="fisheye"):
        fgcal.CameraModel([600, 600, 320, 240], [640, 480], "fisheye", [])


def test_detect_and_pnp_on_a_rendered_numpy_image():
    cam, T = camera(), board_pose()
    image = fgcal.render_board(cam, TARGET, T, supersampling=3, blur_sigma=0.6, noise_sigma=2.0, seed=4)
    assert image.dtype == np.uint8 and image.shape == (544, 1024)
    det = fgcal.CharucoDetector(TARGET).detect(image)
    assert det.ok, det.message
    assert len(det.ids) == TARGET.corner_count and det.corners.shape == (24, 2)
    np.testing.assert_allclose(det.object_points, TARGET.corner_positions()[det.ids])
    # the detected corners are where the camera projects them
    truth_px = cam.project_points((T[:3, :3] @ det.object_points.T).T + T[:3, 3])
    assert np.sqrt(np.mean(np.sum((det.corners - truth_px) ** 2, axis=1))) < 0.15
    # a BGR copy gives the same detection; a non-contiguous view works too
    bgr = np.dstack([image, image, image])
    np.testing.assert_array_equal(fgcal.CharucoDetector(TARGET).detect(bgr).corners, det.corners)
    wide = np.zeros((544, 2048), np.uint8)
    wide[:, ::2] = image
    np.testing.assert_array_equal(fgcal.CharucoDetector(TARGET).detect(wide[:, ::2]).corners, det.corners)

    est = fgcal.estimate_pose(cam, det, pixel_sigma=0.2)
    assert est.converged and est.rms_px < 0.2
    err = fgcal.se3.minus(T, est.T_cam_marker)
    assert np.linalg.norm(err[3:]) < 1e-3 and np.degrees(np.linalg.norm(err[:3])) < 0.1
    assert np.all(np.linalg.eigvalsh(est.covariance) > 0)
    np.testing.assert_allclose(est.covariance, 0.2**2 * np.linalg.inv(est.JtJ), rtol=1e-6)
    again = fgcal.estimate_pose(cam, det.object_points, det.corners, pixel_sigma=0.2)
    np.testing.assert_allclose(again.T_cam_marker, est.T_cam_marker, atol=1e-12)
    assert est.residuals.shape == (24, 2)


def test_rejected_views_and_bad_images():
    det = fgcal.CharucoDetector(TARGET).detect(np.full((480, 640), 128, np.uint8))
    assert not det.ok and det.status == "no markers"
    with pytest.raises(fgcal.InputError, match="no markers|not ok|detection"):
        fgcal.estimate_pose(camera(), det)
    with pytest.raises(ValueError, match="uint8"):
        fgcal.CharucoDetector(TARGET).detect(np.zeros((480, 640)))
    with pytest.raises(ValueError, match="4 channels"):
        fgcal.CharucoDetector(TARGET).detect(np.zeros((480, 640, 4), np.uint8))
    with pytest.raises(fgcal.InputError, match="DICT_NOPE"):
        fgcal.CharucoTarget(5, 7, 0.04, 0.03, "DICT_NOPE")


def test_detection_releases_the_gil():
    cam = camera("none")
    image = fgcal.render_board(cam, TARGET, board_pose(), supersampling=1)
    big = np.kron(image, np.ones((4, 4), np.uint8))  # 4096 x 2176: long enough to be seen running
    detector = fgcal.CharucoDetector(TARGET)
    assert runs_without_gil(detector.detect, big)


def shared(*parts):
    path = os.path.join(os.environ.get("FGCAL_SHARED_DATA_DIR", ""), *parts)
    if not os.path.exists(path):
        pytest.skip("SKIPPED: shared data not found (FGCAL_SHARED_DATA_DIR)")
    return path


def test_real_photos():
    # OpenCV's tutorial photos: the corners Debian's OpenCV 4.6 finds
    # (expected_detections_opencv46.csv), and poses through the photos' own intrinsics.
    target = fgcal.CharucoTarget(5, 7, 0.04, 0.02, "DICT_6X6_250")
    cam = fgcal.CameraModel([452.5107, 456.7671, 317.7030, 277.7516], [640, 480], "radtan",
                            [0.12137, -1.08547, 1.1787e-4, -4.6241e-4, 2.95426])
    with open(shared("charuco", "expected_detections_opencv46.csv")) as f:
        rows = {r["image"]: r for r in csv.DictReader(f)}
    detector = fgcal.CharucoDetector(target)
    for name in ("img_00.jpg", "img_02.jpg"):
        det = detector.detect_file(shared("charuco", name))
        assert det.ok, det.message
        expected = [int(i) for i in rows[name]["charuco_ids"].split()]
        assert det.ids == expected
        est = fgcal.estimate_pose(cam, det)
        assert est.converged and est.rms_px < 0.6 and 0.1 < est.T_cam_marker[2, 3] < 1.0
