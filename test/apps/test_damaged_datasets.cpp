// Every bad input answered. One small valid simulated dataset is made
// once (40 instants, 2 cameras) and calibrated once; that good calibration.yaml
// and its .urdf.xml snippet are then the "previous result" of every case. Each
// case copies the dataset, damages it one way, runs the real `fgcal calibrate`
// executable into a folder holding that previous result, and checks:
// - the exit code: 2 bad input, 1 valid input that cannot support a
//   calibration, 0 where the damage is tolerated (skipped and counted, or
//   accepted with a warning);
// - the message on stderr: it names the file and the field or line and says
//   what was expected (each case lists the parts it must contain);
// - the previous result: byte-identical after a failing run, replaced by a
//   complete result after a succeeding one; no temporary file is left behind.
#include <catch2/catch.hpp>


#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/results_io.hpp"
#include "fgcal/apps/simulator.hpp"
#include "fgcal/kinematics/robot_model.hpp"
#include "fgcal/vision/charuco_detector.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

// The simulator's two cameras (rig.yaml order): a stereo head's left camera, 1024x544, and an RGB-D camera, 640x480.
constexpr const char* kCam0 = "multisense_left";
constexpr const char* kCam1 = "xtion_rgb";

/// Runs `fgcal calibrate DATASET -o OUTPUT [extra]`.
CliRun calibrate(const fs::path& dataset, const fs::path& output, const fs::path& scratch, const std::string& extra = "") {
  return runCommand(FGCAL_EXE,
                    "calibrate " + quoted(dataset.string()) + " -o " + quoted(output.string()) + " --threads 2 " + extra,
                    scratch);
}

// ---- Text surgery on rig.yaml / joints.csv ------------------------------------

/// Replaces the value of the `occurrence`-th line "<indent>[- ]key:" and every
/// following line indented deeper than the key (a block value) by " value".
std::string setField(const std::string& text, const std::string& key, const std::string& value, int occurrence = 0) {
  std::vector<std::string> ls;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);) ls.push_back(l);
  int seen = 0;
  for (std::size_t i = 0; i < ls.size(); ++i) {
    const std::string& l = ls[i];
    std::size_t indent = l.find_first_not_of(' ');
    if (indent == std::string::npos) continue;
    std::size_t k = indent;
    if (l.compare(k, 2, "- ") == 0) k += 2;
    if (l.compare(k, key.size() + 1, key + ":") != 0) continue;
    if (seen++ != occurrence) continue;
    const std::size_t key_indent = k;
    ls[i] = l.substr(0, k + key.size() + 1) + " " + value;
    std::size_t j = i + 1;
    while (j < ls.size()) {
      const std::size_t ind = ls[j].find_first_not_of(' ');
      if (ind == std::string::npos || ind <= key_indent) break;
      // "- [..]" rows of a block matrix sit at the key's indent + 2
      ++j;
    }
    ls.erase(ls.begin() + static_cast<std::ptrdiff_t>(i + 1), ls.begin() + static_cast<std::ptrdiff_t>(j));
    std::string out;
    for (const auto& x : ls) out += x + "\n";
    return out;
  }
  FAIL("rig.yaml has no key " << key << " (occurrence " << occurrence << ")");
  return text;
}

/// Line of `text` starting with `prefix` (the YAML keys' line numbers are checked against it).
int lineOf(const std::string& text, const std::string& needle) {
  std::stringstream ss(text);
  int n = 0;
  for (std::string l; std::getline(ss, l);) {
    ++n;
    if (l.find(needle) != std::string::npos) return n;
  }
  return -1;
}

std::vector<std::string> csvLines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string l; std::getline(ss, l);)
    if (!l.empty()) out.push_back(l);
  return out;
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  for (std::string item; std::getline(ss, item, ',');) f.push_back(item);
  return f;
}

std::string joinCsv(const std::vector<std::string>& f) {
  std::string s;
  for (std::size_t i = 0; i < f.size(); ++i) s += (i ? "," : "") + f[i];
  return s;
}

std::string joinLines(const std::vector<std::string>& ls) {
  std::string s;
  for (const auto& l : ls) s += l + "\n";
  return s;
}

std::vector<fs::path> imagesOf(const fs::path& folder) {
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(folder)) v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}

// ---- The dataset made once ------------------------------------------------------

struct Base {
  fs::path root;  ///< holds ds/ and prev/
  fs::path ds;
  std::string rig, joints;                  ///< rig.yaml and joints.csv text
  std::vector<std::string> chain_joints;    ///< joints of base_link -> marker_link
  std::string prev_yaml, prev_urdf;         ///< the previous good result
  int images_cam0 = 0;
};

const Base& base() {
  static TempDir dir;
  static const Base b = [] {
    Base b;
    b.root = dir.path();
    b.ds = b.root / "ds";
    SimulationOptions sim;
    sim.out_dir = b.ds.string();
    sim.frames = 40;
    sim.cameras = 2;
    sim.seed = 7;
    sim.supersampling = 1;
    simulateDataset(sim);
    b.rig = readFile((b.ds / "rig.yaml").string());
    b.joints = readFile((b.ds / "joints.csv").string());
    const auto model = kinematics::RobotModel::fromFile((b.ds / "robot.urdf").string());
    b.chain_joints = model.chainJointNames("base_link", "lf_foot");
    b.images_cam0 = static_cast<int>(imagesOf(b.ds / kCam0).size());
    // The previous good result every case starts from.
    fs::create_directories(b.root / "prev");
    const CliRun r = calibrate(b.ds, b.root / "prev" / "calibration.yaml", b.root);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    b.prev_yaml = readFile((b.root / "prev" / "calibration.yaml").string());
    b.prev_urdf = readFile((b.root / "prev" / "calibration.urdf.xml").string());
    REQUIRE(!b.prev_yaml.empty());
    REQUIRE(!b.prev_urdf.empty());
    return b;
  }();
  return b;
}

// ---- Cases --------------------------------------------------------------------

struct Case {
  std::string name;
  /// Damages the copied dataset (folder `ds`); may return extra command-line arguments.
  std::function<void(const fs::path& ds)> damage;
  int exit_code;
  /// Parts stderr must contain: the file, the field or line, what was expected.
  std::vector<std::string> message;
  /// When set, the output path (default: <case>/out/calibration.yaml).
  std::function<fs::path(const fs::path& case_dir)> output = nullptr;
};

void writeRig(const fs::path& ds, const std::string& text) { writeFile((ds / "rig.yaml").string(), text); }
void writeJoints(const fs::path& ds, const std::string& text) { writeFile((ds / "joints.csv").string(), text); }

/// joints.csv with cell (row r of the data, column named `joint`) replaced.
std::string setCell(const std::string& csv, int row, const std::string& joint, const std::string& value) {
  auto ls = csvLines(csv);
  const auto header = splitCsv(ls[0]);
  const auto col = std::find(header.begin(), header.end(), joint) - header.begin();
  REQUIRE(col < static_cast<long>(header.size()));
  auto f = splitCsv(ls[static_cast<std::size_t>(row) + 1]);
  f[static_cast<std::size_t>(col)] = value;
  ls[static_cast<std::size_t>(row) + 1] = joinCsv(f);
  return joinLines(ls);
}

/// Overwrites images of `camera` (every `step`-th one, the first `count`) with `make(original)`.
/// A PNG of width x height grey pixels whose IDAT holds only the first rows
/// (zlib stored blocks of zeros): a few hundred bytes that declare gigapixels.
/// A decoder given it would allocate the whole image before finding the data
/// short; fgcal reads the size from IHDR and never decodes it.
std::string bombPng(std::uint32_t width, std::uint32_t height) {
  const auto be32 = [](std::uint32_t v) {
    return std::string{static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
                       static_cast<char>(v)};
  };
  const auto crc32 = [](const std::string& bytes) {
    std::uint32_t c = 0xFFFFFFFFu;
    for (const unsigned char b : bytes) {
      c ^= b;
      for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
  };
  const auto chunk = [&](const std::string& type, const std::string& data) {
    return be32(static_cast<std::uint32_t>(data.size())) + type + data + be32(crc32(type + data));
  };
  // zlib header, one stored block (not final) of 200 zero bytes: the filter byte and pixels of row 0.
  std::string idat = "\x78\x01";
  idat += std::string("\x00\xC8\x00\x37\xFF", 5) + std::string(200, '\0');
  const std::string ihdr = be32(width) + be32(height) + std::string("\x08\x00\x00\x00\x00", 5);  // 8-bit grey
  return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) + chunk("IDAT", idat) + chunk("IEND", "");
}

void rewriteImages(const fs::path& ds, const std::string& camera, int count, int step,
                   const std::function<void(const fs::path&)>& rewrite) {
  const auto files = imagesOf(ds / camera);
  int done = 0;
  for (std::size_t i = 0; i < files.size() && done < count; i += static_cast<std::size_t>(step), ++done)
    rewrite(files[i]);
}

std::vector<Case> cases() {
  const Base& b = base();
  const std::string& rig = b.rig;
  const std::string& joints = b.joints;
  const std::string j0 = b.chain_joints.at(0);
  const std::string j1 = b.chain_joints.at(1);
  const auto rigLine = [&](const std::string& key) { return "line " + std::to_string(lineOf(rig, key)); };
  std::vector<Case> v;

  // ---- rig.yaml ----
  v.push_back({"missing rig.yaml", [](const fs::path& ds) { fs::remove(ds / "rig.yaml"); }, 2,
               {"rig.yaml", "not found"}});
  v.push_back({"YAML syntax error",
               [&](const fs::path& ds) { writeRig(ds, replaced(rig, "target:", "target: [unclosed")); }, 2,
               {"rig.yaml", "line", "YAML"}});
  v.push_back({"a string where a number is expected",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "square_size", "four centimetres")); }, 2,
               {"rig.yaml", "target.square_size", "expected", "number", "'four centimetres'", rigLine("square_size")}});
  v.push_back({"a 3x3 where a 4x4 is expected",
               [&](const fs::path& ds) {
                 writeRig(ds, setField(rig, "T_link_marker", "[[1,0,0],[0,1,0],[0,0,1]]"));
               },
               2, {"rig.yaml", "robot.T_link_marker", "4x4"}});
  v.push_back({"T_link_marker whose rotation is not a rotation",
               [&](const fs::path& ds) {
                 writeRig(ds, setField(rig, "T_link_marker", "[[1,0,0,0],[0,2,0,0],[0,0,1,0.02],[0,0,0,1]]"));
               },
               2, {"rig.yaml", "robot.T_link_marker", "rotation"}});
  v.push_back({"a camera intrinsics list holding a string",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "intrinsics", "[590, fx, 514, 270]")); }, 2,
               {"rig.yaml", "cameras[multisense_left].intrinsics[1]", "number", "'fx'"}});
  v.push_back({"unknown dictionary",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "dictionary", "DICT_9X9_7")); }, 2,
               {"rig.yaml", "dictionary", "DICT_9X9_7", "DICT_4X4_50"}});
  v.push_back({"zero square size", [&](const fs::path& ds) { writeRig(ds, setField(rig, "square_size", "0")); }, 2,
               {"rig.yaml", "target.square_size", "> 0"}});
  v.push_back({"negative pixel sigma",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "pixel_sigma", "-0.5", 1)); }, 2,
               {"rig.yaml", "cameras[xtion_rgb].pixel_sigma", "> 0", "-0.5"}});
  v.push_back({"negative mount sigma",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "mount_sigma", "[-0.002, 0.01]")); }, 2,
               {"rig.yaml", "robot.mount_sigma[0]", ">= 0"}});
  v.push_back({"zero encoder sigma", [&](const fs::path& ds) { writeRig(ds, setField(rig, "encoder_sigma", "0")); },
               2, {"rig.yaml", "robot.encoder_sigma", "> 0"}});
  v.push_back({"negative resolution",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "resolution", "[-1024, 544]")); }, 2,
               {"rig.yaml", "cameras[multisense_left].resolution[0]", ">= 1"}});
  v.push_back({"marker size not smaller than square size",
               [&](const fs::path& ds) {
                 writeRig(ds, setField(setField(rig, "square_size", "0.03"), "marker_size", "0.03"));
               },
               2, {"rig.yaml", "target.marker_size", "smaller than its square"}});
  v.push_back({"distortion list of the wrong length",
               [&](const fs::path& ds) {
                 writeRig(ds, setField(rig, "distortion_coeffs", "[0.1, 0.01, 0.001]", 1));
               },
               2, {"rig.yaml", "cameras[xtion_rgb].distortion_coeffs", "expected 4 numbers", "got 3"}});
  v.push_back({"URDF file missing", [](const fs::path& ds) { fs::remove(ds / "robot.urdf"); }, 2,
               {"rig.yaml", "robot.urdf", "robot.urdf", "does not exist"}});

  // ---- URDF ----
  v.push_back({"URDF that is not XML",
               [](const fs::path& ds) { writeFile((ds / "robot.urdf").string(), "robot: {this is: yaml}\n"); }, 2,
               {"robot.urdf", "XML"}});
  v.push_back({"URDF that lacks the marker link",
               [](const fs::path& ds) {
                 const std::string u = readFile((ds / "robot.urdf").string());
                 std::string out = u;
                 for (std::size_t p; (p = out.find("\"lf_foot\"")) != std::string::npos;)
                   out.replace(p, 9, "\"lf_toe\"");
                 writeFile((ds / "robot.urdf").string(), out);
               },
               2, {"robot.urdf", "lf_foot"}});
  v.push_back({"rig.yaml names a base link the URDF lacks",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "base_link", "torso")); }, 2,
               {"rig.yaml", "robot.base_link", "expected a link of", "robot.urdf", "got 'torso'", "closest links: ",
                rigLine("base_link")}});
  // The closest names are ranked by similarity, not listed in the URDF's order.
  v.push_back({"rig.yaml names the marker link in the wrong case",
               [&](const fs::path& ds) { writeRig(ds, setField(rig, "marker_link", "LF_FOOT")); }, 2,
               {"rig.yaml", "robot.marker_link", "got 'LF_FOOT'", "closest links: lf_foot,", rigLine("marker_link")}});

  // ---- joints.csv ----
  v.push_back({"joints.csv lacks a chain joint column",
               [&, j1](const fs::path& ds) {
                 auto ls = csvLines(joints);
                 const auto header = splitCsv(ls[0]);
                 const auto col = static_cast<std::size_t>(std::find(header.begin(), header.end(), j1) - header.begin());
                 for (auto& l : ls) {
                   auto f = splitCsv(l);
                   f.erase(f.begin() + static_cast<std::ptrdiff_t>(col));
                   l = joinCsv(f);
                 }
                 writeJoints(ds, joinLines(ls));
               },
               2, {"joints.csv", "line 1", j1, "expected a column for every joint"}});
  v.push_back({"joints.csv with extra unknown columns (accepted, warned)",
               [&](const fs::path& ds) {
                 auto ls = csvLines(joints);
                 ls[0] += ",battery_voltage";
                 for (std::size_t i = 1; i < ls.size(); ++i) ls[i] += ",24.1";
                 writeJoints(ds, joinLines(ls));
               },
               0, {"note [input]", "joints.csv", "battery_voltage", "ignored"}});
  v.push_back({"joints.csv with a non-numeric value",
               [&, j0](const fs::path& ds) { writeJoints(ds, setCell(joints, 9, j0, "0.1x")); }, 2,
               {"joints.csv", "line 11", "column " + j0, "expected a number", "'0.1x'"}});
  v.push_back({"joints.csv with NaN and inf (images skipped and counted)",
               [&, j0, j1](const fs::path& ds) {
                 // Every row of the first tenth of the log: the images in that span cannot be used.
                 std::string csv = joints;
                 const int rows = static_cast<int>(csvLines(joints).size()) - 1;
                 for (int r = 0; r < rows / 10; ++r) csv = setCell(csv, r, r % 2 ? j0 : j1, r % 2 ? "nan" : "-inf");
                 writeJoints(ds, csv);
               },
               0, {"joints.csv", "NaN/inf", "skipped", "invalid joint values"}});
  v.push_back({"joints.csv with a duplicate stamp",
               [&](const fs::path& ds) {
                 auto ls = csvLines(joints);
                 auto f = splitCsv(ls[5]);
                 f[0] = splitCsv(ls[4])[0];
                 ls[5] = joinCsv(f);
                 writeJoints(ds, joinLines(ls));
               },
               2, {"joints.csv", "line 6", "stamp_ns", "strictly increasing", "again"}});
  v.push_back({"joints.csv with a decreasing stamp",
               [&](const fs::path& ds) {
                 auto ls = csvLines(joints);
                 std::swap(ls[20], ls[21]);
                 writeJoints(ds, joinLines(ls));
               },
               2, {"joints.csv", "line 22", "stamp_ns", "strictly increasing"}});
  v.push_back({"empty joints.csv", [](const fs::path& ds) { writeJoints(ds, ""); }, 2,
               {"joints.csv", "line 1", "header", "empty file"}});
  v.push_back({"joints.csv with a header only",
               [&](const fs::path& ds) { writeJoints(ds, csvLines(joints)[0] + "\n"); }, 2,
               {"joints.csv", "at least one data row"}});
  v.push_back({"joints.csv missing", [](const fs::path& ds) { fs::remove(ds / "joints.csv"); }, 2,
               {"joints.csv", "not found"}});

  // ---- Camera folders and images ----
  v.push_back({"camera folder missing", [](const fs::path& ds) { fs::remove_all(ds / kCam1); }, 2,
               {kCam1, std::string("image folder of camera '") + kCam1 + "'", "not found"}});
  v.push_back({"camera folder empty",
               [](const fs::path& ds) {
                 fs::remove_all(ds / kCam1);
                 fs::create_directories(ds / kCam1);
               },
               2, {kCam1, std::string("no images of camera '") + kCam1 + "'", "<stamp_ns>.png", "empty"}});
  v.push_back({"non-image files in a camera folder (skipped, warned)",
               [](const fs::path& ds) {
                 writeFile((ds / kCam0 / "notes.txt").string(), "taken on a sunny day\n");
                 writeFile((ds / kCam0 / ".DS_Store").string(), "x");
                 fs::create_directories(ds / kCam0 / "old");
               },
               0, {"note [input]", kCam0, "skipped 3 entries", "notes.txt"}});
  v.push_back({"truncated and corrupt images (skipped and counted)",
               [](const fs::path& ds) {
                 rewriteImages(ds, kCam0, 3, 5, [](const fs::path& p) {
                   const std::string bytes = readFile(p.string());
                   writeFile(p.string(), bytes.substr(0, bytes.size() / 3));  // truncated
                 });
                 rewriteImages(ds, kCam1, 2, 3, [](const fs::path& p) {
                   writeFile(p.string(), std::string("\x89PNG\r\n\x1a\n", 8) + std::string(300, '\x5a'));  // corrupt
                 });
                 writeFile((ds / kCam1 / "1.png").string(), "");  // empty file (also outside the joint span)
               },
               0, {"unreadable image"}});
  v.push_back({"a few images of another size (skipped and counted)",
               [](const fs::path& ds) {
                 rewriteImages(ds, kCam0, 2, 7, [](const fs::path& p) {
                   cv::Mat img = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
                   cv::Mat half;
                   cv::resize(img, half, cv::Size(img.cols / 2, img.rows / 2));
                   cv::imwrite(p.string(), half);
                 });
               },
               0, {"2 wrong image size"}});
  v.push_back({"a decompression bomb: a tiny PNG whose header declares 32000x32000 (never decoded, counted)",
               [](const fs::path& ds) {
                 rewriteImages(ds, kCam0, 1, 1,
                               [](const fs::path& p) { writeFile(p.string(), bombPng(32000, 32000)); });
               },
               0, {"1 wrong image size"}});  // decoded, its cut IDAT would make it unreadable
  v.push_back({"every image of a camera of another size than rig.yaml says",
               [](const fs::path& ds) {
                 rewriteImages(ds, kCam1, 1000, 1, [](const fs::path& p) {
                   cv::Mat img = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
                   cv::Mat half;
                   cv::resize(img, half, cv::Size(img.cols / 2, img.rows / 2));
                   cv::imwrite(p.string(), half);
                 });
               },
               2, {"rig.yaml", "cameras[xtion_rgb].resolution", "640x480", "320x240"}});
  v.push_back({"a camera that never sees the board",
               [](const fs::path& ds) {
                 rewriteImages(ds, kCam1, 1000, 1, [](const fs::path& p) {
                   cv::Mat img = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
                   cv::imwrite(p.string(), cv::Mat(img.size(), CV_8U, cv::Scalar(128)));
                 });
               },
               1, {std::string("camera ") + kCam1, "usable in 0 of", "no board (e.g. ", ".png", "at least 3 needed"}});
  v.push_back({"no instant has enough corners",
               [](const fs::path& ds) {
                 // Each image whited out but for the board's first two corners and the squares around them.
                 const vision::CharucoDetector detector(vision::CharucoTarget{5, 7, 0.04, 0.03, "DICT_4X4_50"});
                 for (const char* cam : {kCam0, kCam1})
                   rewriteImages(ds, cam, 1000, 1, [&](const fs::path& p) {
                     const cv::Mat img = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
                     cv::Mat out(img.size(), CV_8U, cv::Scalar(255));
                     const auto det = detector.detect(img);
                     std::vector<vision::Vec2> keep;
                     for (std::size_t k = 0; k < det.ids.size(); ++k)
                       if (det.ids[k] <= 1) keep.push_back(det.corners[k]);
                     if (keep.size() == 2) {
                       const double m = 0.9 * (keep[1] - keep[0]).norm();
                       const cv::Rect box(cv::Point(int(std::min(keep[0].x(), keep[1].x()) - m), int(std::min(keep[0].y(), keep[1].y()) - m)),
                                          cv::Point(int(std::max(keep[0].x(), keep[1].x()) + m), int(std::max(keep[0].y(), keep[1].y()) + m)));
                       const cv::Rect r = box & cv::Rect(0, 0, img.cols, img.rows);
                       img(r).copyTo(out(r));
                     }
                     cv::imwrite(p.string(), out);
                   });
               },
               1, {std::string("camera ") + kCam0, "usable in 0 of", "too few corners", "at least 3 needed"}});
  v.push_back({"all instants at the same joint positions (degenerate motion)",
               [&](const fs::path& ds) {
                 // A leg that never moved: constant joints, each camera's images all the first one.
                 auto ls = csvLines(joints);
                 const auto first = splitCsv(ls[1]);
                 for (std::size_t i = 2; i < ls.size(); ++i) {
                   auto f = first;
                   f[0] = splitCsv(ls[i])[0];
                   ls[i] = joinCsv(f);
                 }
                 writeJoints(ds, joinLines(ls));
                 for (const char* cam : {kCam0, kCam1}) {
                   const auto files = imagesOf(ds / cam);
                   // The middle image: the board is in view there.
                   const fs::path keep = files[files.size() / 2];
                   for (const auto& f : files)
                     if (f != keep) fs::copy_file(keep, f, fs::copy_options::overwrite_existing);
                 }
               },
               1, {"degenerate motion", "barely move", "cannot be told apart", "--fix-mount"}});
  v.push_back({"output folder that does not exist", [](const fs::path&) {}, 2,
               {"no_such_folder", "does not exist"},
               [](const fs::path& case_dir) { return case_dir / "no_such_folder" / "calibration.yaml"; }});
  return v;
}

void runCase(const Case& c, const fs::path& case_dir) {
  const Base& b = base();
  const fs::path ds = case_dir / "ds";
  const fs::path out_dir = case_dir / "out";
  fs::copy(b.ds, ds, fs::copy_options::recursive);
  fs::create_directories(out_dir);
  fs::copy_file(b.root / "prev" / "calibration.yaml", out_dir / "calibration.yaml");
  fs::copy_file(b.root / "prev" / "calibration.urdf.xml", out_dir / "calibration.urdf.xml");
  c.damage(ds);
  const fs::path output = c.output ? c.output(case_dir) : out_dir / "calibration.yaml";

  const CliRun r = calibrate(ds, output, case_dir);
  INFO("case: " << c.name << "\nstderr:\n" << r.err);
  CHECK(r.exit_code == c.exit_code);
  for (const auto& part : c.message) CHECK_THAT(r.err, Catch::Contains(part));
  // Never a crash, never silent.
  CHECK_THAT(r.err, !Catch::Contains("terminate called"));
  if (c.exit_code != 0) CHECK_THAT(r.err, Catch::Contains("fgcal: error: "));

  // The earlier result: untouched by a failing run, replaced whole by a succeeding one.
  const std::string yaml = readFile((out_dir / "calibration.yaml").string());
  const std::string urdf = readFile((out_dir / "calibration.urdf.xml").string());
  if (c.exit_code != 0) {
    CHECK(yaml == b.prev_yaml);
    CHECK(urdf == b.prev_urdf);
  } else {
    CHECK_NOTHROW(loadCalibrationYaml((out_dir / "calibration.yaml").string()));
    CHECK_THAT(urdf, Catch::Contains("<joint"));
  }
  std::vector<std::string> left, temporary;
  for (const auto& e : fs::directory_iterator(out_dir)) left.push_back(e.path().filename().string());
  for (const auto& e : fs::recursive_directory_iterator(out_dir))
    if (e.path().filename().string().find(".tmp") != std::string::npos) temporary.push_back(e.path().string());
  std::sort(left.begin(), left.end());
  CHECK(temporary.empty());
  if (c.exit_code != 0) CHECK(left == std::vector<std::string>{"calibration.urdf.xml", "calibration.yaml"});
  if (c.output) CHECK_FALSE(fs::exists(c.output(case_dir).parent_path()));
  fs::remove_all(ds);
}

}  // namespace

TEST_CASE("damaged datasets: every bad input answered with its exit code and message, no output touched",
          "[apps][errors][damaged]") {
  const std::vector<Case> all = cases();
  REQUIRE(all.size() >= 30);
  TempDir tmp;
  for (std::size_t i = 0; i < all.size(); ++i) {
    DYNAMIC_SECTION(all[i].name) {
      const fs::path case_dir = tmp.path() / ("case" + std::to_string(i));
      fs::create_directories(case_dir);
      runCase(all[i], case_dir);
    }
  }
}
