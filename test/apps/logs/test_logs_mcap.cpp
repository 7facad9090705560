// The MCAP reader and the CDR decoders (test_logs_ros2): the shared
// anymal_small.mcap (zstd chunks, indexed) against its README and
// expected_images.csv, the same file read through its summary and through a
// linear scan, the MCAP files rosbag2 itself wrote against their
// metadata.yaml, and the small fixtures of fixtures/ (written by the public
// MCAP/CDR writers, fixtures/make_mcap_fixtures.mjs): lz4, no summary, no
// chunks and no footer, big-endian CDR, shared topics, foreign encodings, and
// one damaged file per error the reader must report.
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fgcal_test/files.hpp"
#include "fgcal_test/sha256.hpp"
#include "fgcal_test/shared_data.hpp"

namespace fs = std::filesystem;
using namespace fgcal::logs;

namespace {

const std::string kFixtures = FGCAL_LOGS_FIXTURES;

using fgcal::test::sha256Hex;

// ---- helpers ----------------------------------------------------------------
struct Msg {
  std::string topic;
  std::uint64_t index = 0;
  std::int64_t record_ns = 0;
  std::vector<std::uint8_t> data;
};

std::vector<Msg> readAll(BagReader& bag, const std::vector<std::string>& topics = {}) {
  std::vector<Msg> out;
  bag.read(topics, [&](const RawMessage& m) {
    out.push_back({m.topic->name, m.index, m.record_ns, std::vector<std::uint8_t>(m.data, m.data + m.size)});
    return true;
  });
  return out;
}

/// A scratch copy of `src` holding its first `keep` bytes (a damaged file).
class CutCopy {
 public:
  CutCopy(const std::string& src, std::uint64_t keep, const std::string& name) {
    path_ = (fs::temp_directory_path() / ("fgcal_test_logs_" + std::to_string(::getpid()) + "_" + name)).string();
    std::ifstream in(src, std::ios::binary);
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    std::vector<char> buf(1 << 20);
    while (keep > 0 && in) {
      in.read(buf.data(), static_cast<std::streamsize>(std::min<std::uint64_t>(keep, buf.size())));
      out.write(buf.data(), in.gcount());
      keep -= static_cast<std::uint64_t>(in.gcount());
    }
  }
  ~CutCopy() {
    std::error_code ec;
    fs::remove(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::uint64_t le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

/// summary_start of an MCAP file's footer.
std::uint64_t summaryStart(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  std::array<std::uint8_t, 37> tail{};
  in.seekg(static_cast<std::streamoff>(size - 37));
  in.read(reinterpret_cast<char*>(tail.data()), 37);
  REQUIRE(tail[0] == 0x02);  // the Footer record
  return le64(tail.data() + 9);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const LogError& e) {
    return e.what();
  }
  return "(no LogError)";
}

RawMessage rawOf(const TopicInfo& t, const std::vector<std::uint8_t>& bytes, std::uint64_t index = 0) {
  RawMessage m;
  m.topic = &t;
  m.index = index;
  m.data = bytes.data();
  m.size = bytes.size();
  return m;
}

}  // namespace

// ---- anymal_small.mcap --------------------------------------------------------

TEST_CASE("MCAP: anymal_small.mcap lists its 5 topics with types, counts and record spans", "[logs][mcap]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const auto bag = openBag(dir + "/anymal_small.mcap");
  CHECK_THAT(bag->format(), Catch::Contains("MCAP") && Catch::Contains("zstd") && Catch::Contains("ros2"));
  const std::vector<std::pair<std::string, std::string>> want = {
      {"/cam0/camera_info", "sensor_msgs/msg/CameraInfo"},
      {"/cam0/image_raw", "sensor_msgs/msg/Image"},
      {"/cam1/camera_info", "sensor_msgs/msg/CameraInfo"},
      {"/cam1/image_raw/compressed", "sensor_msgs/msg/CompressedImage"},
      {"/joint_states", "sensor_msgs/msg/JointState"}};
  REQUIRE(bag->topics().size() == want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    const TopicInfo& t = bag->topics()[i];
    CHECK(t.name == want[i].first);
    CHECK(t.type == want[i].second);
    CHECK(t.serialization == Serialization::Cdr);
    CHECK(t.message_count == (t.name == "/joint_states" ? 4121u : 40u));
    // The schema text rosbag2 stores: the type's .msg, then its dependencies.
    CHECK_THAT(t.definition, Catch::Contains("MSG: std_msgs/Header"));
  }
  // The spans come from the message indexes; they must equal what reading gives.
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> span;
  bag->read({}, [&](const RawMessage& m) {
    auto [it, fresh] = span.emplace(m.topic->name, std::make_pair(m.record_ns, m.record_ns));
    it->second.first = std::min(it->second.first, m.record_ns);
    it->second.second = std::max(it->second.second, m.record_ns);
    return true;
  });
  for (const auto& t : bag->topics()) {
    CHECK(t.first_record_ns == span[t.name].first);
    CHECK(t.last_record_ns == span[t.name].second);
  }
}

TEST_CASE("MCAP: anymal_small.mcap joint states match the README", "[logs][mcap][cdr]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const auto bag = openBag(dir + "/anymal_small.mcap");
  const std::string file = bag->path();
  std::vector<JointState> all;
  std::uint64_t expect_index = 0;
  std::int64_t last_record = 0;
  bag->read({"/joint_states"}, [&](const RawMessage& m) {
    CHECK(m.index == expect_index++);
    CHECK(m.record_ns >= last_record);  // storage order is record order here
    last_record = m.record_ns;
    const JointState js = decodeJointState(m, file);
    // record time = header stamp + 1..8 ms of latency
    CHECK(m.record_ns - js.header.stamp_ns >= 1000000);
    CHECK(m.record_ns - js.header.stamp_ns <= 8000000);
    CHECK(decodeHeaderStamp(m, file) == js.header.stamp_ns);
    all.push_back(js);
    return true;
  });
  REQUIRE(all.size() == 4121);
  const std::vector<std::string> names = {"LF_HAA", "LF_HFE", "LF_KFE", "RF_HAA", "RF_HFE", "RF_KFE",
                                          "LH_HAA", "LH_HFE", "LH_KFE", "RH_HAA", "RH_HFE", "RH_KFE"};
  for (const auto& js : all) {
    REQUIRE(js.name == names);
    REQUIRE(js.position.size() == 12);
    REQUIRE(js.velocity.empty());
    REQUIRE(js.effort.empty());
    REQUIRE(js.header.frame_id.empty());
  }
  // Storage order is not stamp order: the first and last samples by stamp.
  const auto [lo, hi] = std::minmax_element(all.begin(), all.end(), [](const JointState& a, const JointState& b) {
    return a.header.stamp_ns < b.header.stamp_ns;
  });
  CHECK(lo->header.stamp_ns == 1700877873968399947);
  CHECK(hi->header.stamp_ns == 1700877894568399947);
  CHECK(lo->position[0] == Approx(-0.0864595).margin(5e-8));
  CHECK(lo->position[1] == Approx(-0.9345635).margin(5e-8));
  CHECK(lo->position[2] == Approx(-1.4634263).margin(5e-8));
  CHECK(hi->position[0] == Approx(-0.1972075).margin(5e-8));
  CHECK(hi->position[1] == Approx(-0.3466659).margin(5e-8));
  CHECK(hi->position[2] == Approx(-1.3700862).margin(5e-8));
  std::size_t swapped = 0;
  for (std::size_t i = 1; i < all.size(); ++i) swapped += all[i].header.stamp_ns < all[i - 1].header.stamp_ns;
  CHECK(swapped > 0);
}

TEST_CASE("MCAP: anymal_small.mcap images equal expected_images.csv byte for byte", "[logs][mcap][cdr]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  struct Row {
    std::string topic, header, record, width, height, step, format, bytes, sha;
  };
  std::vector<Row> rows;
  {
    std::ifstream csv(dir + "/expected_images.csv");
    std::string line;
    std::getline(csv, line);  // header
    while (std::getline(csv, line)) {
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
      REQUIRE(f.size() == 10);
      if (f[7].size() >= 2 && f[7].front() == '"') f[7] = f[7].substr(1, f[7].size() - 2);
      rows.push_back({f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8], f[9]});
    }
  }
  REQUIRE(rows.size() == 80);
  // The csv is sorted by camera; find each message's row by topic and record time.
  std::map<std::pair<std::string, std::string>, const Row*> by_record;
  for (const Row& r : rows) by_record[{r.topic, r.record}] = &r;
  REQUIRE(by_record.size() == rows.size());
  const auto bag = openBag(dir + "/anymal_small.mcap");
  std::size_t next = 0;
  bag->read({"/cam0/image_raw", "/cam1/image_raw/compressed"}, [&](const RawMessage& m) {
    const auto it = by_record.find({m.topic->name, std::to_string(m.record_ns)});
    REQUIRE(it != by_record.end());
    const Row& r = *it->second;
    ++next;
    if (r.topic == "/cam0/image_raw") {
      const Image im = decodeImage(m, bag->path());
      CHECK(std::to_string(im.header.stamp_ns) == r.header);
      CHECK(std::to_string(im.width) == r.width);
      CHECK(std::to_string(im.height) == r.height);
      CHECK(std::to_string(im.step) == r.step);
      CHECK(im.encoding == r.format);
      CHECK(!im.is_bigendian);
      CHECK(im.header.frame_id == "cam0_optical_frame");
      CHECK(std::to_string(im.data.size()) == r.bytes);
      CHECK(sha256Hex(im.data) == r.sha);
    } else {
      const CompressedImage ci = decodeCompressedImage(m, bag->path());
      CHECK(std::to_string(ci.header.stamp_ns) == r.header);
      CHECK(ci.format == "mono8; jpeg compressed ");  // with its trailing space
      CHECK(ci.format == r.format);
      CHECK(ci.header.frame_id == "cam1_optical_frame");
      CHECK(std::to_string(ci.data.size()) == r.bytes);
      CHECK(sha256Hex(ci.data) == r.sha);
    }
    return true;
  });
  CHECK(next == rows.size());
}

TEST_CASE("MCAP: anymal_small.mcap camera infos equal rig.yaml", "[logs][mcap][cdr]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const YAML::Node rig = YAML::LoadFile(dir + "/rig.yaml");
  const auto bag = openBag(dir + "/anymal_small.mcap");
  for (int cam = 0; cam < 2; ++cam) {
    const YAML::Node c = rig["cameras"][cam];
    const std::string name = c["name"].as<std::string>();
    const auto in = c["intrinsics"].as<std::vector<double>>();
    const auto dist = c["distortion_coeffs"].as<std::vector<double>>();
    int n = 0;
    bag->read({"/" + name + "/camera_info"}, [&](const RawMessage& m) {
      const CameraInfo ci = decodeCameraInfo(m, bag->path());
      ++n;
      CHECK(ci.header.frame_id == name + "_optical_frame");
      CHECK(ci.header.stamp_ns != m.record_ns);
      CHECK(ci.width == 640);
      CHECK(ci.height == 480);
      CHECK(ci.distortion_model == "plumb_bob");
      REQUIRE(ci.d.size() == 5);
      for (int i = 0; i < 4; ++i) CHECK(ci.d[static_cast<std::size_t>(i)] == dist[static_cast<std::size_t>(i)]);
      CHECK(ci.d[4] == 0.0);
      const std::array<double, 9> k = {in[0], 0, in[2], 0, in[1], in[3], 0, 0, 1};
      CHECK(ci.k == k);
      CHECK(ci.r == (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
      CHECK(ci.p == (std::array<double, 12>{in[0], 0, in[2], 0, 0, in[1], in[3], 0, 0, 0, 1, 0}));
      CHECK(ci.binning_x == 0);
      CHECK(ci.binning_y == 0);
      return true;
    });
    CHECK(n == 40);
  }
}

TEST_CASE("MCAP: the same messages through the summary and through a linear scan", "[logs][mcap]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const std::string path = dir + "/anymal_small.mcap";
  // Everything before the summary: the data section ends with DataEnd, as a
  // file whose writer stopped before writing its summary and footer.
  const CutCopy cut(path, summaryStart(path), "anymal_no_summary.mcap");
  const auto indexed = openBag(path);
  const auto scanned = openBag(cut.path());
  CHECK_THAT(indexed->format(), Catch::Contains("indexed"));
  CHECK_THAT(scanned->format(), Catch::Contains("no summary"));
  REQUIRE(indexed->topics().size() == scanned->topics().size());
  for (std::size_t i = 0; i < indexed->topics().size(); ++i) {
    const TopicInfo &a = indexed->topics()[i], &b = scanned->topics()[i];
    CHECK(a.name == b.name);
    CHECK(a.type == b.type);
    CHECK(a.definition == b.definition);
    CHECK(a.message_count == b.message_count);
    CHECK(a.first_record_ns == b.first_record_ns);
    CHECK(a.last_record_ns == b.last_record_ns);
  }
  const auto ma = readAll(*indexed), mb = readAll(*scanned);
  REQUIRE(ma.size() == 4281);
  REQUIRE(ma.size() == mb.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < ma.size(); ++i)
    differ += ma[i].topic != mb[i].topic || ma[i].index != mb[i].index || ma[i].record_ns != mb[i].record_ns ||
              ma[i].data != mb[i].data;
  CHECK(differ == 0);
  CHECK(indexed->startNs() == scanned->startNs());
  CHECK(indexed->endNs() == scanned->endNs());
}

TEST_CASE("MCAP: reading stops when the callback returns false", "[logs][mcap]") {
  const auto bag = openBag(kFixtures + "/small_lz4.mcap");
  int n = 0;
  bag->read({}, [&](const RawMessage&) { return ++n < 3; });
  CHECK(n == 3);
}

// ---- MCAP files written by rosbag2 --------------------------------------------

TEST_CASE("MCAP: rosbag2's own MCAP files list the topics and counts of their metadata.yaml", "[logs][mcap]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/rosbag2_tests/resources/mcap");
  for (const std::string bagdir : {"cdr_test", "bag_with_topics_and_service_events"}) {
    INFO(bagdir);
    const YAML::Node meta = YAML::LoadFile(dir + "/" + bagdir + "/metadata.yaml")["rosbag2_bagfile_information"];
    const std::string file = dir + "/" + bagdir + "/" + meta["relative_file_paths"][0].as<std::string>();
    const auto bag = openBag(file);
    CHECK_THAT(bag->format(), Catch::Contains("MCAP"));
    std::map<std::string, std::pair<std::string, std::uint64_t>> want;
    for (const auto& t : meta["topics_with_message_count"])
      want[t["topic_metadata"]["name"].as<std::string>()] = {t["topic_metadata"]["type"].as<std::string>(),
                                                             t["message_count"].as<std::uint64_t>()};
    std::map<std::string, std::pair<std::string, std::uint64_t>> got;
    for (const auto& t : bag->topics()) got[t.name] = {t.type, t.message_count};
    CHECK(got == want);
    // Every message reads; the test_msgs types are listed and refused by the
    // sensor_msgs decoders with a LogError naming the type.
    std::map<std::string, std::uint64_t> read_counts;
    std::uint64_t total = 0;
    bag->read({}, [&](const RawMessage& m) {
      CHECK(m.index == read_counts[m.topic->name]++);
      ++total;
      CHECK_THAT(errorOf([&] { (void)decodeJointState(m, file); }),
                 Catch::Contains(m.topic->type) && Catch::Contains("sensor_msgs/JointState"));
      return true;
    });
    CHECK(total == meta["message_count"].as<std::uint64_t>());
    for (const auto& t : bag->topics()) CHECK(read_counts[t.name] == t.message_count);
    CHECK(bag->startNs() == meta["starting_time"]["nanoseconds_since_epoch"].as<std::int64_t>());
    CHECK(bag->endNs() - bag->startNs() == meta["duration"]["nanoseconds"].as<std::int64_t>());
  }
}

// ---- the small fixtures (public writers) ----------------------------------------

namespace {

constexpr std::int64_t kT0 = 1700000000;

void checkSmallTopics(const BagReader& bag) {
  std::vector<std::string> names;
  for (const auto& t : bag.topics()) names.push_back(t.name);
  CHECK(names == std::vector<std::string>{"/be/camera_info", "/be/image_raw", "/be/image_raw/compressed",
                                          "/be/joint_states", "/cam0/camera_info", "/cam0/image_raw",
                                          "/cam1/image_raw/compressed", "/joint_states", "/log_json", "/no_schema"});
  const TopicInfo* js = bag.findTopic("/joint_states");
  REQUIRE(js);
  CHECK(js->type == "sensor_msgs/msg/JointState");
  CHECK(js->message_count == 6);  // two channels, 4 + 2 messages, merged
  CHECK(js->first_record_ns == (kT0 + 0) * 1000000000 + 250000000 + 3000000);
  CHECK(js->last_record_ns == (kT0 + 11) * 1000000000 + 250000011 + 3000000 + 1000);
  CHECK(bag.findTopic("/be/camera_info")->message_count == 2);
  CHECK(bag.findTopic("/log_json")->type == "example.Log (message encoding json)");
  CHECK(bag.findTopic("/log_json")->message_count == 1);
  CHECK(bag.findTopic("/no_schema")->type.empty());
  CHECK(bag.findTopic("/cam0/image_raw")->definition.find("uint32 height") != std::string::npos);
}

void checkSmallMessages(BagReader& bag) {
  const std::string file = bag.path();
  for (const std::string prefix : {"", "/be"}) {
    INFO("topics " << (prefix.empty() ? "little-endian" : "big-endian"));
    int n = 0;
    bag.read({prefix + "/joint_states"}, [&](const RawMessage& m) {
      const JointState js = decodeJointState(m, file);
      const int i = prefix.empty() && m.index >= 4 ? static_cast<int>(m.index) + 6 : static_cast<int>(m.index);
      CHECK(js.header.stamp_ns == (kT0 + i) * 1000000000 + 250000000 + i);
      CHECK(decodeHeaderStamp(m, file) == js.header.stamp_ns);
      CHECK(js.name == std::vector<std::string>{"LF_HAA", "LF_HFE", "LF_KFE"});
      CHECK(js.position == std::vector<double>{0.5 + i, -0.25 * i, 1e-3 * i});
      CHECK(js.velocity.empty());
      CHECK(js.effort.empty());
      ++n;
      return true;
    });
    CHECK(n == (prefix.empty() ? 6 : 2));
    n = 0;
    bag.read({prefix.empty() ? "/cam0/image_raw" : "/be/image_raw"}, [&](const RawMessage& m) {
      const Image im = decodeImage(m, file);
      const auto i = static_cast<std::uint8_t>(m.index);
      CHECK(im.header.stamp_ns == (kT0 + i) * 1000000000 + 500000000);
      CHECK(im.header.frame_id == "cam0_optical_frame");
      CHECK(im.height == 2);
      CHECK(im.width == 3);
      CHECK(im.step == 3);
      CHECK(im.encoding == "mono8");
      CHECK(!im.is_bigendian);
      CHECK(im.data == std::vector<std::uint8_t>{i, 1, 2, 3, 4, static_cast<std::uint8_t>(255 - i)});
      ++n;
      return true;
    });
    CHECK(n == 2);
    n = 0;
    bag.read({prefix.empty() ? "/cam1/image_raw/compressed" : "/be/image_raw/compressed"}, [&](const RawMessage& m) {
      const CompressedImage ci = decodeCompressedImage(m, file);
      const auto i = static_cast<std::uint8_t>(m.index);
      CHECK(ci.header.frame_id == "cam1_optical_frame");
      CHECK(ci.format == "mono8; jpeg compressed ");
      CHECK(ci.data == std::vector<std::uint8_t>{0xff, 0xd8, 0xff, i, 0xff, 0xd9});
      ++n;
      return true;
    });
    CHECK(n == 2);
    n = 0;
    bag.read({prefix.empty() ? "/cam0/camera_info" : "/be/camera_info"}, [&](const RawMessage& m) {
      const CameraInfo ci = decodeCameraInfo(m, file);
      CHECK(ci.header.stamp_ns == (kT0 + static_cast<std::int64_t>(m.index)) * 1000000000 + 500000000);
      CHECK(ci.width == 640);
      CHECK(ci.height == 480);
      CHECK(ci.distortion_model == "plumb_bob");
      CHECK(ci.d == std::vector<double>{-0.2238976, 0.0879509, -0.00045, -0.0004179, 0});
      CHECK(ci.k == (std::array<double, 9>{444.6463, 0, 324.8444, 0, 444.3995, 240.985, 0, 0, 1}));
      CHECK(ci.r == (std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1}));
      CHECK(ci.p == (std::array<double, 12>{444.6463, 0, 324.8444, 0, 0, 444.3995, 240.985, 0, 0, 0, 1, 0}));
      ++n;
      return true;
    });
    CHECK(n == 2);
  }
  // A json channel is listed and readable as bytes, but no CDR decoder takes it.
  bag.read({"/log_json"}, [&](const RawMessage& m) {
    CHECK(std::string(reinterpret_cast<const char*>(m.data), m.size) == R"({"level":2,"msg":"hello"})");
    CHECK_THAT(errorOf([&] { (void)decodeHeaderStamp(m, file); }), Catch::Contains("json"));
    CHECK_THAT(errorOf([&] { (void)decodeImage(m, file); }), Catch::Contains("json"));
    return true;
  });
}

}  // namespace

TEST_CASE("MCAP: lz4 chunks, shared topics, big-endian CDR and a json channel", "[logs][mcap][cdr]") {
  const auto bag = openBag(kFixtures + "/small_lz4.mcap");
  CHECK_THAT(bag->format(), Catch::Contains("lz4") && Catch::Contains("indexed"));
  checkSmallTopics(*bag);
  checkSmallMessages(*bag);
}

TEST_CASE("MCAP: files without a summary, chunks, chunk indexes or footer read like the indexed one", "[logs][mcap]") {
  const auto indexed = openBag(kFixtures + "/small_lz4.mcap");
  const auto all = readAll(*indexed);
  REQUIRE(all.size() == 22);
  for (const std::string name :
       {"small_zstd_nosummary.mcap", "small_unchunked_cut.mcap", "small_unchunked_indexed.mcap"}) {
    INFO(name);
    const auto bag = openBag(kFixtures + "/" + name);
    // The indexed unchunked file has a summary but no chunk index to count by: it is scanned too.
    CHECK_THAT(bag->format(), Catch::Contains(name == "small_unchunked_indexed.mcap" ? "indexed" : "no summary"));
    checkSmallTopics(*bag);
    checkSmallMessages(*bag);
    const auto got = readAll(*bag);
    REQUIRE(got.size() == all.size());
    for (std::size_t i = 0; i < all.size(); ++i) {
      CHECK(got[i].topic == all[i].topic);
      CHECK(got[i].index == all[i].index);
      CHECK(got[i].record_ns == all[i].record_ns);
      CHECK(got[i].data == all[i].data);
    }
  }
}

// ---- damaged files --------------------------------------------------------------

TEST_CASE("MCAP: each damaged file gives its LogError", "[logs][mcap][errors]") {
  const auto readFile = [](const std::string& name, const ReadLimits& limits = {}) {
    return errorOf([&] {
      const auto bag = openBag(kFixtures + "/" + name, limits);
      (void)readAll(*bag);
    });
  };
  SECTION("unknown compression, named") {
    CHECK_THAT(readFile("bad_compression.mcap"), Catch::Contains("bad_compression.mcap") &&
                                                     Catch::Contains("chunk at offset") && Catch::Contains("brotli"));
  }
  SECTION("chunk CRC mismatch, naming the chunk") {
    CHECK_THAT(readFile("bad_crc.mcap"), Catch::Contains("chunk at offset") && Catch::Contains("CRC"));
  }
  SECTION("zstd chunk shorter than its uncompressed_size") {
    CHECK_THAT(readFile("short_zstd.mcap"), Catch::Contains("chunk at offset") && Catch::Contains("uncompressed_size"));
  }
  SECTION("lz4 chunk longer than its uncompressed_size") {
    CHECK_THAT(readFile("long_lz4.mcap"), Catch::Contains("chunk at offset") && Catch::Contains("more than"));
  }
  SECTION("a chunk larger than ReadLimits::max_chunk_bytes, indexed or scanned") {
    ReadLimits small;
    small.max_chunk_bytes = 900;  // above every schema record, below every chunk
    CHECK_THAT(readFile("small_lz4.mcap", small),
               Catch::Contains("chunk at offset") && Catch::Contains("limit of 900"));
    CHECK_THAT(readFile("small_zstd_nosummary.mcap", small),
               Catch::Contains("chunk at offset") && Catch::Contains("limit of 900"));
  }
  SECTION("a topic not in the file, listing those that are") {
    const auto bag = openBag(kFixtures + "/small_lz4.mcap");
    CHECK_THAT(errorOf([&] {
                 (void)readAll(*bag, {"/cam0/image_raw", "/imu"});
               }),
               Catch::Contains("topic /imu: not in the bag; its topics are: ") &&
                   Catch::Contains("/cam0/image_raw, /cam1/image_raw/compressed"));
  }
  SECTION("cut inside a chunk: the record's offset and declared length") {
    // The no-summary file is three zstd chunks; cut in the middle of one.
    const std::string src = kFixtures + "/small_zstd_nosummary.mcap";
    const CutCopy cut(src, fgcal::test::readFile(src).size() / 2, "cut_chunk.mcap");
    CHECK_THAT(errorOf([&] { (void)openBag(cut.path()); }),
               Catch::Contains("offset ") && Catch::Contains("Chunk record") && Catch::Contains("cut short"));
  }
  SECTION("cut inside a record header or a message") {
    const std::string src = kFixtures + "/small_unchunked_cut.mcap";
    const auto size = fgcal::test::readFile(src).size();
    for (std::uint64_t drop : {1u, 5u, 12u}) {
      const CutCopy cut(src, size - drop, "cut_message.mcap");
      CHECK_THAT(errorOf([&] { (void)openBag(cut.path()); }),
                 Catch::Contains("offset ") && Catch::Contains("cut short"));
    }
  }
  SECTION("an indexed file whose data section was damaged: every prefix fails cleanly or reads") {
    // Cutting an indexed file anywhere loses its footer: it is then scanned,
    // and either reads what it has (cut between records) or names the offset.
    const std::string src = kFixtures + "/small_lz4.mcap";
    const auto size = fgcal::test::readFile(src).size();
    int refused = 0, read = 0;
    for (std::uint64_t keep = 0; keep < size; keep += 97) {
      const CutCopy cut(src, keep, "cut_any.mcap");
      try {
        const auto bag = openBag(cut.path());
        (void)readAll(*bag);
        ++read;
      } catch (const LogError& e) {
        CHECK_THAT(e.what(), Catch::Contains("cut_any.mcap"));
        ++refused;
      }
    }
    CHECK(refused > 0);
  }
  SECTION("no Header record after the magic") {
    const std::string src = kFixtures + "/small_lz4.mcap";
    const CutCopy cut(src, 8, "magic_only.mcap");
    CHECK_THAT(errorOf([&] { (void)openBag(cut.path()); }), Catch::Contains("offset 8"));
  }
}

// ---- CDR decoding errors ------------------------------------------------------

TEST_CASE("CDR: damaged messages give a LogError naming topic, message and field", "[logs][cdr][errors]") {
  const auto bag = openBag(kFixtures + "/small_lz4.mcap");
  std::map<std::string, std::vector<std::uint8_t>> first;
  bag->read({}, [&](const RawMessage& m) {
    first.emplace(m.topic->name, std::vector<std::uint8_t>(m.data, m.data + m.size));
    return true;
  });
  const TopicInfo& js_topic = *bag->findTopic("/joint_states");
  const TopicInfo& info_topic = *bag->findTopic("/cam0/camera_info");
  const auto js = first.at("/joint_states");
  const auto be_js = first.at("/be/joint_states");
  const auto info = first.at("/cam0/camera_info");

  SECTION("every truncation of a message is refused, never read past") {
    for (const auto* pair : {&js, &be_js}) {
      for (std::size_t n = 0; n < pair->size(); ++n) {
        std::vector<std::uint8_t> cut(pair->begin(), pair->begin() + static_cast<std::ptrdiff_t>(n));
        CHECK_THAT(errorOf([&] { (void)decodeJointState(rawOf(js_topic, cut, 7), "x.mcap"); }),
                   Catch::Contains("x.mcap") && Catch::Contains("topic /joint_states, message 7"));
      }
    }
    for (std::size_t n = 0; n < info.size(); ++n) {
      std::vector<std::uint8_t> cut(info.begin(), info.begin() + static_cast<std::ptrdiff_t>(n));
      CHECK_THAT(errorOf([&] { (void)decodeCameraInfo(rawOf(info_topic, cut), "x.mcap"); }),
                 Catch::Contains("CDR field"));
    }
  }
  SECTION("nanosec >= 1e9") {
    auto bad = js;
    const std::uint32_t ns = 1000000000u;
    std::memcpy(bad.data() + 8, &ns, 4);  // after the encapsulation header and sec (little-endian host)
    CHECK_THAT(errorOf([&] { (void)decodeHeaderStamp(rawOf(js_topic, bad), "x.mcap"); }),
               Catch::Contains("nanosec") && Catch::Contains("1000000000"));
  }
  SECTION("a negative stamp") {
    auto bad = js;
    const std::int32_t sec = -5;
    std::memcpy(bad.data() + 4, &sec, 4);
    CHECK_THAT(errorOf([&] { (void)decodeJointState(rawOf(js_topic, bad), "x.mcap"); }), Catch::Contains("-5"));
  }
  SECTION("an encapsulation other than plain CDR") {
    auto bad = js;
    bad[1] = 0x03;  // PL_CDR_LE
    CHECK_THAT(errorOf([&] { (void)decodeJointState(rawOf(js_topic, bad), "x.mcap"); }),
               Catch::Contains("encapsulation") && Catch::Contains("00 03"));
  }
  SECTION("a string length running past the end") {
    auto bad = js;
    const std::uint32_t huge = 0x7fffffff;
    std::memcpy(bad.data() + 12, &huge, 4);  // frame_id's length
    CHECK_THAT(errorOf([&] { (void)decodeJointState(rawOf(js_topic, bad), "x.mcap"); }),
               Catch::Contains("header.frame_id") && Catch::Contains("2147483647"));
  }
  SECTION("a string without its NUL") {
    auto bad = js;
    // frame_id is "" (length 1, a NUL); make that byte non-zero
    REQUIRE(bad[16] == 0);
    bad[16] = 'x';
    CHECK_THAT(errorOf([&] { (void)decodeJointState(rawOf(js_topic, bad), "x.mcap"); }), Catch::Contains("NUL"));
  }
  // The same checks as the ROS 1 decoders make (test_logs_ros1.cpp).
  SECTION("is_bigendian above 1") {
    const TopicInfo& image_topic = *bag->findTopic("/cam0/image_raw");
    auto bad = first.at("/cam0/image_raw");
    const auto u32 = [&](std::size_t at) {
      std::uint32_t v;
      std::memcpy(&v, bad.data() + at, 4);  // little-endian CDR on a little-endian host
      return v;
    };
    // encapsulation(4) sec nanosec frame_id; then, aligned to 4, height, width, encoding, is_bigendian
    const std::size_t after_header = (16 + u32(12) + 3) / 4 * 4;
    const std::size_t encoding = after_header + 8;
    const std::size_t flag = encoding + 4 + u32(encoding);
    REQUIRE(bad.at(flag) == 0);
    bad[flag] = 2;
    CHECK_THAT(errorOf([&] { (void)decodeImage(rawOf(image_topic, bad, 3), "x.mcap"); }),
               Catch::Equals("x.mcap: topic /cam0/image_raw, message 3: "
                             "CDR field is_bigendian: expected a bool (0 or 1), found 2"));
  }
  SECTION("roi.do_rectify above 1") {
    auto bad = info;
    REQUIRE(bad.back() == 0);  // do_rectify, the message's last byte
    bad.back() = 2;
    CHECK_THAT(errorOf([&] { (void)decodeCameraInfo(rawOf(info_topic, bad, 2), "x.mcap"); }),
               Catch::Equals("x.mcap: topic /cam0/camera_info, message 2: "
                             "CDR field roi.do_rectify: expected a bool (0 or 1), found 2"));
  }
  SECTION("a sequence count larger than the message") {
    auto bad = js;
    const std::uint32_t huge = 0xffffffffu;
    std::memcpy(bad.data() + 20, &huge, 4);  // name's count, after frame_id (4 + 1 + 3 padding)
    CHECK_THAT(errorOf([&] { (void)decodeJointState(rawOf(js_topic, bad), "x.mcap"); }),
               Catch::Contains("name") && Catch::Contains("4294967295"));
  }
}

TEST_CASE("MCAP: a damaged summary is refused; a damaged end magic falls back to a scan", "[logs][mcap][errors]") {
  const std::string src = kFixtures + "/small_lz4.mcap";
  const std::string bytes = fgcal::test::readFile(src);
  const auto patched = [&](std::size_t at, const std::string& name) {
    std::string b = bytes;
    b[at] = static_cast<char>(b[at] ^ 0x01);
    const std::string path = (fs::temp_directory_path() / ("fgcal_test_logs_" + std::to_string(::getpid()) + "_" + name)).string();
    std::ofstream(path, std::ios::binary).write(b.data(), static_cast<std::streamsize>(b.size()));
    return path;
  };
  SECTION("one bit flipped inside the summary section: its CRC names the damage") {
    const std::string path = patched(static_cast<std::size_t>(summaryStart(src)) + 20, "bad_summary.mcap");
    CHECK_THAT(errorOf([&] { (void)openBag(path); }),
               Catch::Contains("bad_summary.mcap") && Catch::Contains("summary section CRC mismatch"));
    fs::remove(path);
  }
  SECTION("the end magic damaged: the footer cannot be trusted, the data section is scanned") {
    const std::string path = patched(bytes.size() - 1, "bad_end_magic.mcap");
    const auto bag = openBag(path);
    CHECK_THAT(bag->format(), Catch::Contains("no summary"));
    checkSmallTopics(*bag);
    const auto indexed = openBag(src);
    const auto a = readAll(*indexed), b = readAll(*bag);
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i].data == b[i].data);
    fs::remove(path);
  }
}
