// Dataset folders: listing, sorting, subsets, skipped files and every error.
#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "fgcal/apps/dataset.hpp"
#include "fgcal/kinematics/default_robot.hpp"
#include "rig_fixture.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {
// A small valid dataset: cam0 with 3 PNGs, cam1 with 2 JPEGs (one uppercase),
// both seeing stamp 2000.
void makeDataset(const TempDir& tmp) {
  writeFile(tmp / "rig.yaml", kValidRig);
  writeFile(tmp / "robot.urdf", kinematics::defaultRobotUrdf());
  writeFile(tmp / "joints.csv", "stamp_ns,lf_haa_joint,lf_hfe_joint,lf_kfe_joint\n0,0,0,0\n10000,1,1,1\n");
  for (const char* f : {"cam0/3000.png", "cam0/1000.png", "cam0/2000.png", "cam1/2000.JPG", "cam1/500.jpeg"})
    writeFile(tmp / f, "not decoded here");
}
}  // namespace

TEST_CASE("parseImageFileName", "[apps][dataset]") {
  int64_t s = 0;
  CHECK(parseImageFileName("1700000000123456789.png", &s));
  CHECK(s == 1700000000123456789LL);
  CHECK(parseImageFileName("42.JPEG", &s));
  CHECK(s == 42);
  CHECK(parseImageFileName("0042.Jpg", &s));
  CHECK(s == 42);
  for (const char* bad : {"abc.png", "12.bmp", "12", ".png", "12.png.bak", "-12.png", "1e3.png", "12 .png",
                          "99999999999999999999.png", "notes.txt"})
    CHECK_FALSE(parseImageFileName(bad, &s));
}

TEST_CASE("dataset: a valid folder", "[apps][dataset]") {
  TempDir tmp;
  makeDataset(tmp);
  const Dataset ds = loadDataset(tmp.path().string());
  CHECK(ds.root == fs::absolute(tmp.path()).lexically_normal().string());
  CHECK(ds.rig.cameras.size() == 2);
  CHECK(ds.rig.robot.urdf == (tmp.path() / "robot.urdf").string());
  CHECK(ds.joints.stamps_ns.size() == 2);
  REQUIRE(ds.images.size() == 5);
  const std::vector<std::pair<int64_t, std::string>> expected{
      {500, "cam1"}, {1000, "cam0"}, {2000, "cam0"}, {2000, "cam1"}, {3000, "cam0"}};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    CHECK(ds.images[i].stamp_ns == expected[i].first);
    CHECK(ds.images[i].camera == expected[i].second);
  }
  CHECK(ds.images[3].path == (tmp.path() / "cam1" / "2000.JPG").string());
  CHECK(ds.warnings.empty());
}

TEST_CASE("dataset: other files in a camera folder are skipped and counted", "[apps][dataset]") {
  TempDir tmp;
  makeDataset(tmp);
  writeFile(tmp / "cam0/notes.txt", "x");
  writeFile(tmp / "cam0/left_1000.png", "x");
  fs::create_directories(tmp.path() / "cam0" / "thumbs");
  writeFile(tmp / "ground_truth.yaml", "cameras: {}\n");  // not a camera folder: ignored
  const Dataset ds = loadDataset(tmp.path().string());
  CHECK(ds.images.size() == 5);
  REQUIRE(ds.warnings.size() == 1);
  CHECK_THAT(ds.warnings[0], Catch::Contains("cam0") && Catch::Contains("skipped 3 entries"));
}

TEST_CASE("dataset: rig and joints warnings are passed on", "[apps][dataset]") {
  TempDir tmp;
  makeDataset(tmp);
  writeFile(tmp / "rig.yaml", kValidRig + "operator: me\n");
  writeFile(tmp / "joints.csv", "stamp_ns,lf_haa_joint,lf_hfe_joint,lf_kfe_joint\n0,0,nan,0\n10000,1,1,1\n");
  const Dataset ds = loadDataset(tmp.path().string());
  REQUIRE(ds.warnings.size() == 2);
  CHECK_THAT(ds.warnings[0], Catch::Contains("operator"));
  CHECK_THAT(ds.warnings[1], Catch::Contains("NaN"));
}

TEST_CASE("dataset: camera subset", "[apps][dataset]") {
  TempDir tmp;
  makeDataset(tmp);
  const Dataset ds = loadDataset(tmp.path().string(), {"cam1"});
  REQUIRE(ds.rig.cameras.size() == 1);
  CHECK(ds.rig.cameras[0].name == "cam1");
  CHECK(ds.images.size() == 2);
  fs::remove_all(tmp.path() / "cam0");  // an unselected camera's folder is not needed
  CHECK(loadDataset(tmp.path().string(), {"cam1"}).images.size() == 2);
  CHECK_INPUT_ERROR(loadDataset(tmp.path().string(), {"cam1", "cam7"}), "rig.yaml", "--cameras", "'cam7'",
                    "closest cameras: cam0, cam1");
}

TEST_CASE("dataset: a camera whose intrinsics only a bag can give is refused in a folder", "[apps][dataset][bag]") {
  TempDir tmp;
  makeDataset(tmp);
  const std::string from = "    distortion_model: equidistant\n    intrinsics: [400, 400, 330.5, 250.25]\n"
                           "    distortion_coeffs: [0.1, 0.01, 0.001, 0.0001]\n    resolution: [752, 480]\n";
  writeFile(tmp / "rig.yaml", replaced(kValidRig, from, "    camera_info_topic: /cam1/camera_info\n"));
  CHECK_INPUT_ERROR(loadDataset(tmp.path().string()), "rig.yaml", "cameras[cam1].intrinsics", "/cam1/camera_info",
                    "intrinsics_file", "line 24");
  // Not selected: not needed.
  CHECK(loadDataset(tmp.path().string(), {"cam0"}).rig.cameras.size() == 1);
}

TEST_CASE("dataset: every error names the file or folder", "[apps][dataset]") {
  TempDir tmp;
  makeDataset(tmp);
  const std::string dir = tmp.path().string();
  SECTION("folder missing") {
    CHECK_INPUT_ERROR(loadDataset(tmp / "nope"), "nope", "", "dataset folder not found");
  }
  SECTION("a file instead of a folder") {
    CHECK_INPUT_ERROR(loadDataset(tmp / "rig.yaml"), "rig.yaml", "", "expected a dataset folder", "got a file");
  }
  SECTION("rig.yaml missing") {
    fs::remove(tmp.path() / "rig.yaml");
    CHECK_INPUT_ERROR(loadDataset(dir), "rig.yaml", "", "not found");
  }
  SECTION("joints.csv missing") {
    fs::remove(tmp.path() / "joints.csv");
    CHECK_INPUT_ERROR(loadDataset(dir), "joints.csv", "", "not found", "stamp_ns");
  }
  SECTION("URDF missing") {
    fs::remove(tmp.path() / "robot.urdf");
    CHECK_INPUT_ERROR(loadDataset(dir), "rig.yaml", "robot.urdf", "existing URDF",
                      (tmp.path() / "robot.urdf").string());
  }
  SECTION("invalid rig.yaml is reported with its field") {
    writeFile(tmp / "rig.yaml", replaced(kValidRig, "pixel_sigma: 0.5", "pixel_sigma: -1"));
    CHECK_INPUT_ERROR(loadDataset(dir), "rig.yaml", "cameras[cam0].pixel_sigma", "> 0");
  }
  SECTION("invalid joints.csv is reported with its line") {
    writeFile(tmp / "joints.csv", "stamp_ns,a\n1,x\n");
    CHECK_INPUT_ERROR(loadDataset(dir), "joints.csv", "line 2, column a", "'x'");
  }
  SECTION("camera folder missing") {
    fs::remove_all(tmp.path() / "cam1");
    CHECK_INPUT_ERROR(loadDataset(dir), "cam1", "", "image folder of camera 'cam1'", "not found");
  }
  SECTION("camera folder empty") {
    fs::remove_all(tmp.path() / "cam1");
    fs::create_directories(tmp.path() / "cam1");
    CHECK_INPUT_ERROR(loadDataset(dir), "cam1", "", "no images of camera 'cam1'", "<stamp_ns>.png", "empty");
  }
  SECTION("camera folder with only other files") {
    fs::remove_all(tmp.path() / "cam1");
    writeFile(tmp / "cam1/readme.md", "x");
    CHECK_INPUT_ERROR(loadDataset(dir), "cam1", "", "no images", "1 other entries, e.g. readme.md");
  }
  SECTION("two images with one stamp") {
    writeFile(tmp / "cam0/2000.jpg", "x");
    CHECK_INPUT_ERROR(loadDataset(dir), "cam0", "", "one image per stamp", "2000");
  }
}
