// The error contract: message composition and exit-code classes.
#include <catch2/catch.hpp>

#include "fgcal/apps/errors.hpp"
#include "fgcal/kinematics/errors.hpp"

using namespace fgcal::apps;

TEST_CASE("InputError composes file, location and detail", "[apps][errors]") {
  const InputError e("rig.yaml", "cameras[cam1].distortion_coeffs", "expected 4 numbers for distortion_model radtan, got 5");
  CHECK(std::string(e.what()) ==
        "rig.yaml: cameras[cam1].distortion_coeffs: expected 4 numbers for distortion_model radtan, got 5");
  CHECK(e.file() == "rig.yaml");
  CHECK(e.location() == "cameras[cam1].distortion_coeffs");
  CHECK(std::string(InputError("joints.csv", "", "not found").what()) == "joints.csv: not found");
}

TEST_CASE("exitCodeFor maps exception classes to docs/design.md's exit codes", "[apps][errors]") {
  CHECK(exitCodeFor(InputError("a", "b", "c")) == 2);
  CHECK(exitCodeFor(DataError("too few detections")) == 1);
  CHECK(exitCodeFor(fgcal::kinematics::UrdfError("robot.urdf: no link lf_foot")) == 2);
  CHECK(exitCodeFor(fgcal::kinematics::KinematicsError("unknown joint")) == 2);
  CHECK(exitCodeFor(std::invalid_argument("bad")) == 2);
  CHECK(exitCodeFor(std::runtime_error("something else")) == 1);
}
