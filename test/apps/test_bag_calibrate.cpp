// Calibration and import from robot bags, on the shared ANYmal fixture
// (shared/data/bags/anymal_small: cam0 raw mono8, cam1 JPEG, 40 instants; its
// README says everything about it) stored as a ROS 1 bag, a rosbag2 sqlite3
// folder and an MCAP file:
// - the three bags calibrate to the same camera poses (1e-9), within 3 sigma
//   of ground_truth.yaml; intrinsics left to camera_info give the same result;
// - `fgcal import` keeps compressed images byte for byte and raw ones as PNG
//   whose pixel rows hash to expected_images.csv, writes every joint sample,
//   and calibrating the imported folder gives the bags' result;
// - estimating time offsets (both methods) and joint zero offsets finds the
//   fixture's synchronised, offset-free truth within the estimates' sigma,
//   and names the two joint offsets a 3-joint leg cannot observe;
// - each bad input through the real fgcal command: exit 2, a message naming
//   the bag, topic and message, nothing written.
// The shared rig.yaml has no topic fields: each test writes one derived from
// it (URDF path made absolute) into a scratch folder.
#include <catch2/catch.hpp>

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/calibrate.hpp"
#include "fgcal/apps/corner_calibration.hpp"
#include "fgcal/apps/offset_estimation.hpp"
#include "fgcal/apps/import.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fgcal_test/shared_data.hpp"
#include "logs/ros1_test_support.hpp"  // sha256Hex

using namespace fgcal;
using namespace fgcal::apps;
using fgcal::apps::test::CliRun;
using fgcal::apps::test::quoted;
using fgcal::apps::test::readFile;
using fgcal::apps::test::TempDir;
using fgcal::apps::test::writeFile;
namespace fs = std::filesystem;

namespace {

const char* kCam0Topic = "/cam0/image_raw";
const char* kCam1Topic = "/cam1/image_raw/compressed";

/// The fixture's rig.yaml with each camera's topics, the URDF path absolute.
/// `from_camera_info`: cameras without intrinsics, so the bag's camera_info gives them.
std::string derivedRig(const std::string& fixture, const std::string& cam0_topic = kCam0Topic,
                       const std::string& cam1_topic = kCam1Topic, bool from_camera_info = false) {
  std::istringstream in(readFile(fixture + "/rig.yaml"));
  std::ostringstream out;
  const std::string urdf = fs::canonical(fs::path(fixture) / "../../urdf/anymal_c.urdf").string();
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("  urdf:", 0) == 0) line = "  urdf: " + urdf;
    if (from_camera_info &&
        (line.find("distortion_model:") != std::string::npos || line.find("intrinsics:") != std::string::npos ||
         line.find("distortion_coeffs:") != std::string::npos || line.find("resolution:") != std::string::npos))
      continue;
    out << line << "\n";
    if (line == "  - name: cam0")
      out << "    topic: " << cam0_topic << "\n    camera_info_topic: /cam0/camera_info\n";
    if (line == "  - name: cam1")
      out << "    topic: " << cam1_topic << "\n    camera_info_topic: /cam1/camera_info\n";
  }
  return out.str();
}

struct ExpectedImage {
  std::string camera, encoding, sha;
  std::int64_t stamp = 0;
};

std::vector<ExpectedImage> expectedImages(const std::string& csv) {
  std::vector<ExpectedImage> out;
  std::istringstream in(readFile(csv));
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    // camera,topic,header_stamp_ns,record_time_ns,width,height,step,encoding_or_format,data_bytes,data_sha256
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    REQUIRE(f.size() == 10);
    out.push_back({f[0], f[7], f[9], std::stoll(f[2])});
  }
  return out;
}

std::string rowsSha(const cv::Mat& m) {
  std::vector<std::uint8_t> rows;
  for (int r = 0; r < m.rows; ++r) rows.insert(rows.end(), m.ptr(r), m.ptr(r) + m.cols * m.elemSize());
  return logs::test::sha256Hex(rows.data(), rows.size());
}

/// Every file under `dir` (relative path -> bytes).
std::map<std::string, std::string> filesOf(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = readFile(e.path().string());
  return out;
}

/// The imported folder holds every image of expected_images.csv as the
/// fixture's README says, and every joint sample.
void checkImported(const fs::path& dir, const std::vector<ExpectedImage>& expected) {
  for (const auto& e : expected) {
    INFO(e.camera << " stamp " << e.stamp);
    if (e.camera == "cam1") {  // JPEG, byte for byte
      const std::string bytes = readFile((dir / "cam1" / (std::to_string(e.stamp) + ".jpg")).string());
      REQUIRE(!bytes.empty());
      CHECK(logs::test::sha256Hex(bytes) == e.sha);
    } else {  // raw mono8 -> PNG whose decoded rows are the message's data
      const cv::Mat png = cv::imread((dir / "cam0" / (std::to_string(e.stamp) + ".png")).string(), cv::IMREAD_UNCHANGED);
      REQUIRE(png.type() == CV_8UC1);
      CHECK(rowsSha(png) == e.sha);
    }
  }
  CHECK(std::distance(fs::directory_iterator(dir / "cam0"), fs::directory_iterator()) == 40);
  CHECK(std::distance(fs::directory_iterator(dir / "cam1"), fs::directory_iterator()) == 40);
  const JointLog joints = loadJointsCsv((dir / "joints.csv").string());
  REQUIRE(joints.stamps_ns.size() == 4121);  // every sample, in header-stamp order
  CHECK(joints.names.size() == 12);
  CHECK(joints.stamps_ns.front() == 1700877873968399947);
  CHECK(joints.stamps_ns.back() == 1700877894568399947);
  const int lf_hfe = joints.column("LF_HFE");
  REQUIRE(lf_hfe >= 0);
  CHECK(joints.positions(0, lf_hfe) == -0.9345635);
  CHECK(joints.positions(4120, lf_hfe) == -0.3466659);
}

/// `output` empty: nothing written; else calibration.yaml there and its report beside it.
CalibrateResult calibrate(const std::string& input, const std::string& rig, const std::string& output = "") {
  CalibrateOptions o;
  o.dataset = input;
  o.rig = rig;
  o.threads = 2;
  o.output = output;
  o.write_files = !output.empty();
  o.report = !output.empty();
  std::ostringstream log;
  return runCalibrate(o, log);
}

void checkSamePoses(const CalibrateResult& a, const CalibrateResult& b, const std::string& what) {
  INFO(what);
  REQUIRE(a.output.cameras.size() == b.output.cameras.size());
  for (std::size_t c = 0; c < a.output.cameras.size(); ++c) {
    INFO("camera " << a.output.cameras[c].name);
    const Vec6 d = a.output.cameras[c].T_base_cam.minus(b.output.cameras[c].T_base_cam);
    CHECK(d.cwiseAbs().maxCoeff() < 1e-9);
  }
}

CliRun fgcalCommand(const std::string& args, const fs::path& scratch) {
  return fgcal::apps::test::runCommand(FGCAL_EXE, args, scratch);
}

/// A writable copy of the fixture's db3 file alone (the reader counts its messages itself).
std::string copyDb3(const std::string& fixture, const fs::path& dir) {
  fs::create_directories(dir);
  const fs::path to = dir / "anymal.db3";
  fs::copy_file(fs::path(fixture) / "anymal_small_db3/anymal_small_db3_0.db3", to);
  fs::permissions(to, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  return to.string();
}

/// Runs SQL on a copied db3, as a user editing a bag would.
void execSql(const std::string& db3, const std::string& sql) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(db3.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK);
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  const std::string msg = err ? err : "";
  sqlite3_free(err);
  sqlite3_close(db);
  INFO(sql << ": " << msg);
  REQUIRE(rc == SQLITE_OK);
}

/// Rewrites the CDR payload of the message with that row id.
void patchMessage(const std::string& db3, std::int64_t id, const std::function<void(std::string&)>& edit) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(db3.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  REQUIRE(sqlite3_prepare_v2(db, "SELECT data FROM messages WHERE id = ?", -1, &st, nullptr) == SQLITE_OK);
  sqlite3_bind_int64(st, 1, id);
  REQUIRE(sqlite3_step(st) == SQLITE_ROW);
  std::string blob(static_cast<const char*>(sqlite3_column_blob(st, 0)), static_cast<std::size_t>(sqlite3_column_bytes(st, 0)));
  sqlite3_finalize(st);
  edit(blob);
  REQUIRE(sqlite3_prepare_v2(db, "UPDATE messages SET data = ? WHERE id = ?", -1, &st, nullptr) == SQLITE_OK);
  sqlite3_bind_blob(st, 1, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT);
  sqlite3_bind_int64(st, 2, id);
  REQUIRE(sqlite3_step(st) == SQLITE_DONE);
  sqlite3_finalize(st);
  sqlite3_close(db);
}

/// Row id of the `n`-th message (0-based, storage order) of a topic.
std::int64_t messageId(const std::string& db3, const std::string& topic, int n) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(db3.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  const std::string sql = "SELECT m.id FROM messages m JOIN topics t ON m.topic_id = t.id WHERE t.name = '" + topic +
                          "' ORDER BY m.timestamp, m.id LIMIT 1 OFFSET " + std::to_string(n);
  REQUIRE(sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) == SQLITE_OK);
  REQUIRE(sqlite3_step(st) == SQLITE_ROW);
  const std::int64_t id = sqlite3_column_int64(st, 0);
  sqlite3_finalize(st);
  sqlite3_close(db);
  return id;
}

void replaceOnce(std::string& blob, const std::string& from, const std::string& to) {
  REQUIRE(from.size() == to.size());
  const auto pos = blob.find(from);
  REQUIRE(pos != std::string::npos);
  blob.replace(pos, from.size(), to);
}

}  // namespace

TEST_CASE("ANYmal bags: three formats calibrate alike within 3 sigma of the truth; import keeps the images and "
          "calibrates alike",
          "[bag][e2e]") {
  FGCAL_REQUIRE_SHARED_DATA(fixture, "bags/anymal_small");
  TempDir tmp;
  writeFile(tmp / "rig.yaml", derivedRig(fixture));
  // The MCAP is calibrated with intrinsics left to camera_info (which equal rig.yaml's).
  writeFile(tmp / "rig_info.yaml", derivedRig(fixture, kCam0Topic, kCam1Topic, true));
  REQUIRE(loadRigConfig(tmp / "rig_info.yaml").cameras[0].intrinsics_from_bag);
  const auto expected = expectedImages(fixture + "/expected_images.csv");
  REQUIRE(expected.size() == 80);

  const std::vector<std::pair<std::string, std::string>> bags = {
      {fixture + "/anymal_small.bag", tmp / "rig.yaml"},
      {fixture + "/anymal_small_db3", tmp / "rig.yaml"},
      {fixture + "/anymal_small.mcap", tmp / "rig_info.yaml"}};

  // Import: each bag gives the same folder, images and joints as recorded.
  std::map<std::string, std::string> first_files;
  for (std::size_t b = 0; b < bags.size(); ++b) {
    INFO("import of " << bags[b].first);
    const fs::path out = tmp.path() / ("imported" + std::to_string(b));
    std::ostringstream log;
    const ImportResult r = runImport({bags[b].first, bags[b].second, out.string()}, log);
    CHECK(r.joint_samples == 4121);
    CHECK(r.images.at("cam0") == 40);
    checkImported(out, expected);
    // rig.yaml: intrinsics filled in (from camera_info for the MCAP), URDF relative to the new folder.
    const RigConfig rig = loadRigConfig((out / "rig.yaml").string());
    CHECK(rig.cameras[0].intrinsics == std::array<double, 4>{444.6463, 444.3995, 324.8444, 240.985});
    CHECK(rig.cameras[1].distortion_coeffs == std::vector<double>{-0.2441213, 0.0577736, -3.47e-05, 0.0005702});
    CHECK_FALSE(rig.cameras[0].intrinsics_from_bag);
    CHECK(fs::equivalent(rig.robot.urdf, fs::path(fixture) / "../../urdf/anymal_c.urdf"));
    CHECK_THAT(readFile((out / "rig.yaml").string()), Catch::Contains("  urdf: \"../"));  // relative, not absolute
    auto files = filesOf(out);
    files.erase("rig.yaml");  // the same but for the source of the intrinsics
    if (b == 0) first_files = files;
    else CHECK(files == first_files);  // byte for byte the same dataset from each format
  }

  // Calibrate: the three bags, then the folder imported from the ROS 1 bag.
  const GroundTruth truth = loadGroundTruth(fixture + "/ground_truth.yaml");
  const CalibrateResult ros1 = calibrate(bags[0].first, bags[0].second, tmp / "calibration.yaml");
  // The report's overlay pictures are drawn on images read back from the bag (they are not files).
  CHECK(fs::exists(tmp / "calibration.urdf.xml"));
  CHECK(std::distance(fs::directory_iterator(tmp.path() / "calibration_report" / "images"), fs::directory_iterator()) ==
        6);
  CHECK_THAT(readFile(ros1.report_path), !Catch::Contains("cannot read"));
  for (const CameraResult& cr : ros1.output.cameras) {
    INFO("camera " << cr.name << " against ground_truth.yaml");
    CHECK(cr.images_used == 40);
    // Error in the estimate's own tangent space, against its own 1-sigma.
    const Vec6 err = cr.T_base_cam.minus(truth.T_base_cam.at(cr.name));
    for (int k = 0; k < 6; ++k) CHECK(std::abs(err[k]) < 3.0 * std::sqrt(cr.covariance(k, k)));
  }
  checkSamePoses(ros1, calibrate(bags[1].first, bags[1].second), "rosbag2 sqlite3 vs ROS 1");
  const CalibrateResult mcap = calibrate(bags[2].first, bags[2].second);
  checkSamePoses(ros1, mcap, "MCAP with intrinsics from camera_info vs ROS 1");
  CHECK(mcap.rig.cameras[1].intrinsics == std::array<double, 4>{473.4193, 473.5301, 312.4112, 238.6454});
  checkSamePoses(ros1, calibrate((tmp.path() / "imported0").string(), ""), "imported folder vs ROS 1 bag");
}

// The fixture comes from another simulator: its cameras are exactly
// synchronised with the joint log (identical header stamps, joints at 200 Hz
// with +-50 us stamp jitter and 1 mrad noise) and its encoders have no zero
// offsets. Estimating either must find that, within the estimate's own sigma,
// from a joint log fgcal did not write; the camera poses stay within 3 sigma
// of the truth.
TEST_CASE("ANYmal bag from an independent simulator: the estimated time and joint offsets agree with its "
          "synchronised, offset-free truth",
          "[bag][offsets]") {
  FGCAL_REQUIRE_SHARED_DATA(fixture, "bags/anymal_small");
  TempDir tmp;
  writeFile(tmp / "rig.yaml", derivedRig(fixture));
  const GroundTruth truth = loadGroundTruth(fixture + "/ground_truth.yaml");
  const auto run = [&](Method method, const std::string& estimate) {
    CalibrateOptions o;
    o.dataset = fixture + "/anymal_small.mcap";
    o.rig = tmp / "rig.yaml";
    o.threads = 2;
    o.write_files = false;
    o.report = false;
    o.method = method;
    o.estimate = parseEstimateSet(estimate);
    std::ostringstream log;
    const CalibrateResult r = runCalibrate(o, log);
    for (const CameraResult& cr : r.output.cameras) {
      INFO("camera " << cr.name << " against ground_truth.yaml");
      const Vec6 err = cr.T_base_cam.minus(truth.T_base_cam.at(cr.name));
      for (int k = 0; k < 6; ++k) CHECK(std::abs(err[k]) < 3.0 * std::sqrt(cr.covariance(k, k)));
    }
    return r;
  };

  for (const Method method : {Method::Pnp, Method::Corners}) {
    INFO("--method " << toString(method) << " --estimate time-offset");
    const CalibrateResult r = run(method, "time-offset");
    REQUIRE(r.solution.offsets.time_offsets.size() == 2);
    for (const TimeOffsetEstimate& t : r.solution.offsets.time_offsets) {
      INFO("camera " << t.camera << ": " << t.offset_s * 1e3 << " ms, 1-sigma " << t.sigma_s * 1e3 << " ms");
      CHECK(t.observed);
      // 40 instants of a moving leg pin each offset to about half a millisecond.
      CHECK(t.sigma_s > 0.0);
      CHECK(t.sigma_s < 2e-3);
      CHECK(std::abs(t.offset_s) < 3.0 * t.sigma_s);
    }
  }

  INFO("--estimate joint-offsets");
  const CalibrateResult r = run(Method::Pnp, "joint-offsets");
  REQUIRE(r.solution.offsets.joint_offsets.size() == 3);
  std::map<std::string, JointOffsetEstimate> by_joint;
  for (const JointOffsetEstimate& j : r.solution.offsets.joint_offsets) by_joint[j.joint] = j;
  // The middle joint of the leg is observed; the hip's offset turns every
  // board pose rigidly (the cameras absorb it) and the knee's folds into the
  // mount: both must be named, not returned as numbers.
  const JointOffsetEstimate& hfe = by_joint.at("LF_HFE");
  INFO("LF_HFE: " << hfe.offset_rad * 1e3 << " mrad, 1-sigma " << hfe.sigma_rad * 1e3 << " mrad");
  CHECK(hfe.observed);
  CHECK(hfe.sigma_rad < 5e-3);
  CHECK(std::abs(hfe.offset_rad) < 3.0 * hfe.sigma_rad);
  for (const std::string joint : {"LF_HAA", "LF_KFE"}) {
    INFO(joint);
    CHECK_FALSE(by_joint.at(joint).observed);
    CHECK(std::any_of(r.warnings.begin(), r.warnings.end(), [&](const std::string& w) {
      return w.find("joint " + joint + "'s zero offset is not observed") != std::string::npos;
    }));
  }
}

TEST_CASE("bag: a CompressedImage whose JPEG header declares 32000x32000 is skipped as a wrong image size, never "
          "decoded",
          "[bag][damaged]") {
  FGCAL_REQUIRE_SHARED_DATA(fixture, "bags/anymal_small");
  TempDir tmp;
  const std::string db3 = copyDb3(fixture, tmp.path() / "bomb");
  // cam1's 11th image: the data after the CDR format string becomes a JPEG of
  // 46 bytes (SOI, APP0, SOF0 of 32000 x 32000, EOI) with no scan to decode.
  patchMessage(db3, messageId(db3, kCam1Topic, 10), [](std::string& blob) {
    const std::string format("mono8; jpeg compressed \0", 24);
    const auto at = blob.find(format);
    REQUIRE(at != std::string::npos);
    std::size_t data = at + format.size();
    data += (4 - (data - 4) % 4) % 4;  // CDR alignment, counted after the 4-byte encapsulation header
    const std::string jpeg = std::string("\xFF\xD8\xFF\xE0\x00\x10JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00", 20) +
                             std::string("\xFF\xC0\x00\x0B\x08\x7D\x00\x7D\x00\x01\x01\x11\x00\xFF\xD9", 15);
    const std::uint32_t n = static_cast<std::uint32_t>(jpeg.size());
    blob = blob.substr(0, data) + std::string(reinterpret_cast<const char*>(&n), 4) + jpeg;
  });
  writeFile(tmp / "rig.yaml", derivedRig(fixture));
  const fs::path output = tmp.path() / "out" / "calibration.yaml";
  fs::create_directories(output.parent_path());
  const CliRun cal = fgcalCommand("calibrate " + quoted(db3) + " --rig " + quoted(tmp / "rig.yaml") + " -o " +
                                      quoted(output.string()) + " --threads 2 --no-report",
                                  tmp.path());
  INFO("calibrate stderr: " << cal.err);
  REQUIRE(cal.exit_code == 0);
  CHECK_THAT(cal.err, Catch::Contains("1 wrong image size"));
  const CalibrationOutput out = loadCalibrationYaml(output.string());
  for (const CameraResult& c : out.cameras) {
    INFO(c.name);
    const auto wrong = c.images_skipped.find("wrong image size");
    if (c.name == "cam1") {
      REQUIRE(wrong != c.images_skipped.end());
      CHECK(wrong->second == 1);
    } else {
      CHECK(wrong == c.images_skipped.end());
    }
  }
}

TEST_CASE("bag input errors through the fgcal command: exit 2, bag, topic and message named, nothing written",
          "[bag][errors]") {
  FGCAL_REQUIRE_SHARED_DATA(fixture, "bags/anymal_small");
  TempDir tmp;
  const std::string bag = fixture + "/anymal_small.bag";
  const fs::path out_dir = tmp.path() / "out";
  fs::create_directories(out_dir);

  struct Case {
    std::string name, bag, rig_text;
    std::vector<std::string> expect;
  };
  std::vector<Case> cases;
  cases.push_back({"a topic not in the bag", bag, derivedRig(fixture, "/cam0/image_rect"),
                   {"rig.yaml", "cameras[cam0].topic", "anymal_small.bag", "'/cam0/image_rect'", "not in the bag",
                    "closest topics of that type: /cam0/image_raw", "(line "}});
  cases.push_back({"a wrong message type", bag, derivedRig(fixture, kCam0Topic, "/cam1/camera_info"),
                   {"anymal_small.bag", "/cam1/camera_info", "sensor_msgs/CompressedImage", "sensor_msgs/CameraInfo"}});
  {  // An encoding fgcal cannot read, in cam0's 6th image: "mono8" -> "yuv42" (same length, CDR intact).
    const std::string db3 = copyDb3(fixture, tmp.path() / "encoding");
    patchMessage(db3, messageId(db3, kCam0Topic, 5), [](std::string& blob) {
      replaceOnce(blob, std::string("\x06\x00\x00\x00mono8", 9), std::string("\x06\x00\x00\x00yuv42", 9));
    });
    cases.push_back({"an image encoding fgcal cannot read", db3, derivedRig(fixture),
                     {"anymal.db3", "topic /cam0/image_raw, message 5", "stamp 1700877876767903920", "yuv42", "mono8"}});
  }
  {  // Joint states that end before the first image.
    const std::string db3 = copyDb3(fixture, tmp.path() / "joints");
    execSql(db3, "DELETE FROM messages WHERE timestamp > 1700877874200000000 AND topic_id = "
                 "(SELECT id FROM topics WHERE name = '/joint_states')");
    cases.push_back({"no joint states over the images", db3, derivedRig(fixture),
                     {"anymal.db3", "topic /joint_states", "overlap none of the images"}});
  }
  {  // cam1's image topic left empty.
    const std::string db3 = copyDb3(fixture, tmp.path() / "empty");
    execSql(db3, "DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '" +
                     std::string(kCam1Topic) + "')");
    cases.push_back({"an image topic without messages", db3, derivedRig(fixture),
                     {"anymal.db3", "topic /cam1/image_raw/compressed", "no image messages"}});
  }
  {  // A camera_info whose fx changes half way.
    const std::string db3 = copyDb3(fixture, tmp.path() / "info");
    patchMessage(db3, messageId(db3, "/cam1/camera_info", 20), [](std::string& blob) {
      double fx = 473.4193, moved = 480.0;
      replaceOnce(blob, std::string(reinterpret_cast<const char*>(&fx), 8), std::string(reinterpret_cast<const char*>(&moved), 8));
    });
    cases.push_back({"camera_info changing its intrinsics", db3, derivedRig(fixture),
                     {"anymal.db3", "topic /cam1/camera_info, message 20", "stamp 1700877884268177186", "changed"}});
  }
  {  // A bag cut short: the reader's own error, as exit 2.
    const fs::path cut = tmp.path() / "cut" / "anymal_cut.bag";
    fs::create_directories(cut.parent_path());
    const std::string bytes = readFile(bag);
    writeFile(cut.string(), bytes.substr(0, bytes.size() / 2));
    cases.push_back({"a truncated bag", cut.string(), derivedRig(fixture), {"anymal_cut.bag"}});
  }

  for (const Case& c : cases) {
    SECTION(c.name) {
      writeFile(tmp / "rig.yaml", c.rig_text);
      const fs::path output = out_dir / "calibration.yaml";
      const CliRun cal = fgcalCommand("calibrate " + quoted(c.bag) + " --rig " + quoted(tmp / "rig.yaml") + " -o " +
                                       quoted(output.string()) + " --threads 2",
                                   tmp.path());
      INFO("calibrate stderr: " << cal.err);
      CHECK(cal.exit_code == 2);
      for (const auto& part : c.expect) CHECK_THAT(cal.err, Catch::Contains(part));
      CHECK(fs::is_empty(out_dir));  // no result, no report, no temporary file

      const fs::path dataset = out_dir / "dataset";
      const CliRun imp = fgcalCommand("import " + quoted(c.bag) + " --rig " + quoted(tmp / "rig.yaml") + " --out " +
                                       quoted(dataset.string()),
                                   tmp.path());
      INFO("import stderr: " << imp.err);
      CHECK(imp.exit_code == 2);
      for (const auto& part : c.expect) CHECK_THAT(imp.err, Catch::Contains(part));
      CHECK(fs::is_empty(out_dir));
    }
  }

  SECTION("a bag without --rig, a folder with a missing --rig, and an import over a non-empty folder") {
    const CliRun cal = fgcalCommand("calibrate " + quoted(bag) + " -o " + quoted((out_dir / "c.yaml").string()), tmp.path());
    CHECK(cal.exit_code == 2);
    CHECK_THAT(cal.err, Catch::Contains("--rig"));
    const CliRun folder = fgcalCommand("calibrate " + quoted(tmp.path().string()) + " --rig " + quoted(tmp / "none.yaml") +
                                        " -o " + quoted((out_dir / "c.yaml").string()),
                                    tmp.path());
    CHECK(folder.exit_code == 2);
    CHECK_THAT(folder.err, Catch::Contains("none.yaml") && Catch::Contains("--rig names the rig.yaml"));
    writeFile(tmp / "rig.yaml", derivedRig(fixture));
    writeFile((out_dir / "dataset" / "keep.txt").string(), "earlier work");
    const CliRun imp = fgcalCommand("import " + quoted(bag) + " --rig " + quoted(tmp / "rig.yaml") + " --out " +
                                     quoted((out_dir / "dataset").string()),
                                 tmp.path());
    CHECK(imp.exit_code == 2);
    CHECK_THAT(imp.err, Catch::Contains("not an empty folder"));
    CHECK(readFile((out_dir / "dataset" / "keep.txt").string()) == "earlier work");
    CHECK(std::distance(fs::directory_iterator(out_dir), fs::directory_iterator()) == 1);
    // An --out whose parent folder is missing is refused as every output is: "create it first".
    const CliRun parent = fgcalCommand("import " + quoted(bag) + " --rig " + quoted(tmp / "rig.yaml") + " --out " +
                                           quoted((out_dir / "no_such" / "dataset").string()),
                                       tmp.path());
    CHECK(parent.exit_code == 2);
    CHECK_THAT(parent.err, Catch::Contains("--out: the parent folder") && Catch::Contains("create it first"));
    CHECK(!fs::exists(out_dir / "no_such"));
  }
}

namespace {

// A raw Image whose data are short of step x height: its CDR data length
// (640 x 480 = 307200 bytes, little-endian) says 1000; the bytes after it
// are left as they are (the reader ignores them).
void shortenRawImage(const std::string& db3, int n) {
  patchMessage(db3, messageId(db3, kCam0Topic, n), [](std::string& blob) {
    replaceOnce(blob, std::string("\x00\xb0\x04\x00", 4), std::string("\xe8\x03\x00\x00", 4));
  });
}

// A CompressedImage whose JPEG stream is no image any more: its start-of-image marker zeroed.
void breakJpeg(const std::string& db3, int n) {
  patchMessage(db3, messageId(db3, kCam1Topic, n), [](std::string& blob) {
    replaceOnce(blob, std::string("\xff\xd8\xff", 3), std::string("\x00\x00\x00", 3));
  });
}

}  // namespace

TEST_CASE("damaged image messages, raw or compressed, are skipped and counted alike, named in the summary, the "
          "report and calibration.yaml; most of a camera's damaged is a finding naming its topic",
          "[bag][damaged]") {
  FGCAL_REQUIRE_SHARED_DATA(fixture, "bags/anymal_small");
  TempDir tmp;
  writeFile(tmp / "rig.yaml", derivedRig(fixture));
  const auto calibrate = [&](const std::string& db3, const std::string& out) {
    fs::create_directories(out);
    return fgcalCommand("calibrate " + quoted(db3) + " --rig " + quoted(tmp / "rig.yaml") + " -o " +
                            quoted(out + "/calibration.yaml") + " --threads 2",
                        tmp.path());
  };

  SECTION("one damaged message per camera: the run goes on, and says which") {
    const std::string db3 = copyDb3(fixture, tmp.path() / "one");
    shortenRawImage(db3, 5);
    breakJpeg(db3, 7);
    const std::string out = tmp / "out_one";
    const CliRun r = calibrate(db3, out);
    INFO(r.out << r.err);
    REQUIRE(r.exit_code == 0);
    const std::string all = r.out + r.err;
    CHECK_THAT(all, Catch::Contains("damaged, skipped: ") && Catch::Contains("topic /cam0/image_raw, message 5") &&
                        Catch::Contains("data holds 1000 bytes"));
    CHECK_THAT(all, Catch::Contains("topic /cam1/image_raw/compressed, message 7") &&
                        Catch::Contains("damaged message: cannot be decoded"));
    CHECK_THAT(all, Catch::Contains("(stamp "));
    const std::string cal = readFile(out + "/calibration.yaml");
    // Counted the same way for both kinds, per camera.
    std::size_t count = 0;
    for (std::size_t p = 0; (p = cal.find("unreadable image", p)) != std::string::npos; ++p)
      count += cal.compare(cal.find(':', p), 4, ": 1\n") == 0;
    CHECK(count == 2);
    CHECK(cal.find("damaged_messages") == std::string::npos);  // one of 40 is no finding
    const std::string report = readFile(out + "/calibration_report/index.html");
    CHECK_THAT(report, Catch::Contains("Damaged messages skipped") && Catch::Contains("data holds 1000 bytes"));
  }

  SECTION("most of a camera's messages damaged: a check naming the topic; all of them: unusable, nothing written") {
    const std::string most = copyDb3(fixture, tmp.path() / "most");
    for (int n = 0; n < 25; ++n) breakJpeg(most, n);
    const std::string out = tmp / "out_most";
    const CliRun r = calibrate(most, out);
    INFO(r.out << r.err);
    REQUIRE(r.exit_code == 0);
    CHECK_THAT(r.out + r.err, Catch::Contains("check [damaged_messages] fields: cameras[cam1].topic") &&
                                  Catch::Contains("25 of the 40 images of camera cam1"));
    CHECK_THAT(readFile(out + "/calibration.yaml"), Catch::Contains("damaged_messages"));

    const std::string every = copyDb3(fixture, tmp.path() / "every");
    for (int n = 0; n < 40; ++n) breakJpeg(every, n);
    const std::string out_every = tmp / "out_every";
    const CliRun u = calibrate(every, out_every);
    INFO(u.out << u.err);
    CHECK(u.exit_code == 1);
    CHECK_THAT(u.err, Catch::Contains("verdict: UNUSABLE") &&
                          Catch::Contains("unusable [damaged_messages] fields: cameras[cam1].topic") &&
                          Catch::Contains("nothing is left"));
    CHECK(!fs::exists(out_every + "/calibration.yaml"));
  }
}
