// The ROS 1 bag reader and the ROS 1 message decoders of fgcal::logs.
// Real data: the shared ANYmal bag (lz4), written by ROS's own Python writer
// and documented in shared/data/bags/README.md. Small fixtures:
// fixtures/ros1_{none,bz2,lz4}.bag, also written by ROS's writer
// (fixtures/make_ros1_fixtures.py says what they hold). Damaged bags are made
// here from copies of those, at places found by walking their records.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fgcal_test/shared_data.hpp"
#include "ros1_test_support.hpp"

using namespace fgcal::logs;
using namespace fgcal::logs::test;

namespace {

const std::string kFixtures = std::string(FGCAL_SOURCE_DIR) + "/test/apps/logs/fixtures/";
constexpr std::int64_t kT0 = 1700000000250000000;

/// Everything read() reports about one message, its payload hashed.
struct Seen {
  std::string topic;
  std::uint64_t index = 0;
  std::int64_t record_ns = 0;
  std::string sha;
  bool operator==(const Seen& o) const {
    return topic == o.topic && index == o.index && record_ns == o.record_ns && sha == o.sha;
  }
};

std::vector<Seen> readAll(BagReader& bag, const std::vector<std::string>& topics = {}) {
  std::vector<Seen> out;
  bag.read(topics, [&](const RawMessage& m) {
    out.push_back({m.topic->name, m.index, m.record_ns, sha256Hex(m.data, m.size)});
    return true;
  });
  return out;
}

/// The LogError of `fn`, or a failed test when it throws nothing.
template <class Fn>
LogError errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const LogError& e) {
    return e;
  }
  FAIL("expected a LogError");
  return LogError("", "", "");
}

/// A copy of `bag` whose recording was killed: index_pos 0 in the bag header
/// and the file cut where the index began (what rosbag leaves behind).
std::string unindexedCopy(const std::string& bytes) {
  std::string b = bytes;
  const auto recs = topLevelRecords(b);
  const std::size_t at = recs.front().field_value_pos.at("index_pos");
  std::uint64_t index_pos = 0;
  for (int i = 7; i >= 0; --i) index_pos = index_pos << 8 | static_cast<std::uint8_t>(b[at + static_cast<std::size_t>(i)]);
  REQUIRE(index_pos > 0);
  REQUIRE(index_pos < b.size());
  b.resize(index_pos);
  for (int i = 0; i < 8; ++i) b[at + static_cast<std::size_t>(i)] = 0;
  return b;
}

std::vector<Record> chunksOf(const std::string& bytes) {
  std::vector<Record> chunks;
  for (const auto& r : topLevelRecords(bytes))
    if (r.op() == 0x05) chunks.push_back(r);
  return chunks;
}

/// A limit well above the fixtures' chunks, so damaged sizes cannot allocate much.
ReadLimits smallLimits() {
  ReadLimits l;
  l.max_chunk_bytes = 1 << 20;
  return l;
}

/// Opens, lists, reads every message and decodes the four types.
void readAndDecodeEverything(const std::string& path, const ReadLimits& limits = smallLimits()) {
  auto bag = openBag(path, limits);
  bag->read({}, [&](const RawMessage& m) {
    switch (messageKind(m.topic->type)) {
      case MessageKind::JointState: (void)decodeJointState(m, path); break;
      case MessageKind::Image: (void)decodeImage(m, path); break;
      case MessageKind::CompressedImage: (void)decodeCompressedImage(m, path); break;
      case MessageKind::CameraInfo: (void)decodeCameraInfo(m, path); break;
      case MessageKind::Other: break;
    }
    (void)decodeHeaderStamp(m, path);
    return true;
  });
}

}  // namespace

// ---------------------------------------------------------------------------
// The shared ANYmal bag (lz4, 17 chunks)

// The image checks below trust the tests' own SHA-256 (test/support); these
// are FIPS 180-4's examples: one block, a tail that needs a second padding
// block (56 bytes), and many whole blocks hashed straight from the input.
TEST_CASE("test support: SHA-256 gives FIPS 180-4's digests", "[logs][ros1][support]") {
  CHECK(sha256Hex(std::string()) == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(sha256Hex(std::string("abc")) == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256Hex(std::string("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq")) ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(sha256Hex(std::string(1000000, 'a')) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  const std::vector<std::uint8_t> abc = {'a', 'b', 'c'};
  CHECK(sha256Hex(abc) == sha256Hex(std::string("abc")));
}

TEST_CASE("ANYmal bag: the five topics with their ROS 1 types, counts and record-time spans", "[logs][ros1]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  auto bag = openBag(dir + "/anymal_small.bag");
  CHECK(bag->format().find("ROS 1 bag 2.0") != std::string::npos);
  CHECK(bag->format().find("17 chunk") != std::string::npos);
  CHECK(bag->format().find("lz4") != std::string::npos);
  CHECK(bag->format().find(", indexed") != std::string::npos);
  const auto& t = bag->topics();
  REQUIRE(t.size() == 5);
  const std::vector<std::tuple<std::string, std::string, std::uint64_t>> expected = {
      {"/cam0/camera_info", "sensor_msgs/CameraInfo", 40},
      {"/cam0/image_raw", "sensor_msgs/Image", 40},
      {"/cam1/camera_info", "sensor_msgs/CameraInfo", 40},
      {"/cam1/image_raw/compressed", "sensor_msgs/CompressedImage", 40},
      {"/joint_states", "sensor_msgs/JointState", 4121}};
  for (std::size_t i = 0; i < 5; ++i) {
    INFO(std::get<0>(expected[i]));
    CHECK(t[i].name == std::get<0>(expected[i]));
    CHECK(t[i].type == std::get<1>(expected[i]));
    CHECK(t[i].message_count == std::get<2>(expected[i]));
    CHECK(t[i].serialization == Serialization::Ros1);
    CHECK(t[i].definition.find("Header header") != std::string::npos);
    CHECK(t[i].definition.find("MSG: std_msgs/Header") != std::string::npos);
  }
  // The spans are the exact record times (from the index data), which the
  // messages read agree with.
  std::map<std::string, std::pair<std::int64_t, std::int64_t>> span;
  std::map<std::string, std::uint64_t> count;
  bag->read({}, [&](const RawMessage& m) {
    auto it = span.try_emplace(m.topic->name, m.record_ns, m.record_ns).first;
    it->second.first = std::min(it->second.first, m.record_ns);
    it->second.second = std::max(it->second.second, m.record_ns);
    ++count[m.topic->name];
    return true;
  });
  for (const auto& ti : t) {
    INFO(ti.name);
    CHECK(count[ti.name] == ti.message_count);
    CHECK(span[ti.name].first == ti.first_record_ns);
    CHECK(span[ti.name].second == ti.last_record_ns);
  }
  // First image record time from expected_images.csv.
  CHECK(bag->findTopic("/cam0/image_raw")->first_record_ns == 1700877874273865923);
}

TEST_CASE("ANYmal bag: joint states with the README's first and last samples, by header stamp, not record time",
          "[logs][ros1]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const std::string path = dir + "/anymal_small.bag";
  auto bag = openBag(path);
  std::vector<JointState> js;
  std::vector<std::int64_t> record;
  std::uint64_t expected_index = 0;
  bag->read({"/joint_states"}, [&](const RawMessage& m) {
    CHECK(m.index == expected_index++);
    js.push_back(decodeJointState(m, path));
    record.push_back(m.record_ns);
    CHECK(decodeHeaderStamp(m, path) == js.back().header.stamp_ns);
    return true;
  });
  REQUIRE(js.size() == 4121);
  const std::vector<std::string> names = {"LF_HAA", "LF_HFE", "LF_KFE", "RF_HAA", "RF_HFE", "RF_KFE",
                                          "LH_HAA", "LH_HFE", "LH_KFE", "RH_HAA", "RH_HFE", "RH_KFE"};
  std::size_t first = 0, last = 0, inversions = 0;
  for (std::size_t i = 0; i < js.size(); ++i) {
    REQUIRE(js[i].name == names);
    REQUIRE(js[i].position.size() == 12);
    CHECK(js[i].velocity.empty());
    CHECK(js[i].effort.empty());
    CHECK(js[i].header.frame_id.empty());
    // Record time = header stamp + 1..8 ms of latency (README).
    const std::int64_t latency = record[i] - js[i].header.stamp_ns;
    CHECK(latency >= 1000000);
    CHECK(latency <= 8000000);
    if (js[i].header.stamp_ns < js[first].header.stamp_ns) first = i;
    if (js[i].header.stamp_ns > js[last].header.stamp_ns) last = i;
    if (i > 0 && js[i].header.stamp_ns < js[i - 1].header.stamp_ns) ++inversions;
    if (i > 0) CHECK(record[i] >= record[i - 1]);  // storage order is record-time order
  }
  CHECK(inversions > 0);  // so the storage order is not the header-stamp order
  CHECK(js[first].header.stamp_ns == 1700877873968399947);
  CHECK(js[first].position[0] == Approx(-0.0864595).margin(5e-8));
  CHECK(js[first].position[1] == Approx(-0.9345635).margin(5e-8));
  CHECK(js[first].position[2] == Approx(-1.4634263).margin(5e-8));
  CHECK(js[last].header.stamp_ns == 1700877894568399947);
  CHECK(js[last].position[0] == Approx(-0.1972075).margin(5e-8));
  CHECK(js[last].position[1] == Approx(-0.3466659).margin(5e-8));
  CHECK(js[last].position[2] == Approx(-1.3700862).margin(5e-8));
}

TEST_CASE("ANYmal bag: every image's data bytes hash to expected_images.csv", "[logs][ros1]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const std::string path = dir + "/anymal_small.bag";
  struct Row {
    std::string topic, encoding;
    std::int64_t record_ns = 0;
    std::uint32_t width = 0, height = 0, step = 0;
    std::size_t bytes = 0;
    std::string sha;
    bool seen = false;
  };
  std::map<std::pair<std::string, std::int64_t>, Row> rows;  // (topic, header stamp)
  std::ifstream csv(dir + "/expected_images.csv");
  std::string line;
  std::getline(csv, line);
  while (std::getline(csv, line)) {
    // Comma-separated; a quoted cell ("mono8; jpeg compressed ") holds no comma.
    std::vector<std::string> c(1);
    bool quoted = false;
    for (const char ch : line) {
      if (ch == '"') quoted = !quoted;
      else if (ch == ',' && !quoted) c.emplace_back();
      else c.back() += ch;
    }
    REQUIRE(c.size() == 10);
    const auto u32 = [](const std::string& s) { return s.empty() ? 0u : static_cast<std::uint32_t>(std::stoul(s)); };
    Row r{c[1], c[7], std::stoll(c[3]), u32(c[4]), u32(c[5]), u32(c[6]), std::stoul(c[8]), c[9]};
    rows[{c[1], std::stoll(c[2])}] = r;
  }
  REQUIRE(rows.size() == 80);
  auto bag = openBag(path);
  std::size_t images = 0;
  bag->read({"/cam0/image_raw", "/cam1/image_raw/compressed"}, [&](const RawMessage& m) {
    ++images;
    std::int64_t stamp = 0;
    std::string sha, encoding, frame;
    std::size_t bytes = 0;
    if (m.topic->name == "/cam0/image_raw") {
      const Image im = decodeImage(m, path);
      stamp = im.header.stamp_ns, sha = sha256Hex(im.data.data(), im.data.size()), bytes = im.data.size();
      encoding = im.encoding, frame = im.header.frame_id;
      CHECK(im.width == 640);
      CHECK(im.height == 480);
      CHECK(im.step == 640);
      CHECK_FALSE(im.is_bigendian);
      CHECK(frame == "cam0_optical_frame");
    } else {
      const CompressedImage ci = decodeCompressedImage(m, path);
      stamp = ci.header.stamp_ns, sha = sha256Hex(ci.data.data(), ci.data.size()), bytes = ci.data.size();
      encoding = ci.format, frame = ci.header.frame_id;
      CHECK(frame == "cam1_optical_frame");
      REQUIRE(ci.data.size() > 2);
      CHECK(ci.data[0] == 0xff);  // JPEG SOI
      CHECK(ci.data[1] == 0xd8);
    }
    const auto it = rows.find({m.topic->name, stamp});
    INFO(m.topic->name << " message " << m.index << " stamp " << stamp);
    REQUIRE(it != rows.end());
    CHECK_FALSE(it->second.seen);
    it->second.seen = true;
    CHECK(sha == it->second.sha);
    CHECK(bytes == it->second.bytes);
    CHECK(encoding == it->second.encoding);
    if (m.topic->name == "/cam0/image_raw") {
      CHECK(it->second.width == 640);
      CHECK(it->second.step == 640);
    }
    CHECK(m.record_ns == it->second.record_ns);
    CHECK(m.record_ns != stamp);
    return true;
  });
  CHECK(images == 80);
  for (const auto& [key, r] : rows) CHECK(r.seen);
  // The README's first and last image stamps.
  CHECK(rows.begin()->first.second == 1700877874268399947);
  CHECK(rows.count({"/cam0/image_raw", 1700877894267864430}) == 1);
}

TEST_CASE("ANYmal bag: CameraInfo K, D, R, P equal rig.yaml, with the image stamps", "[logs][ros1]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const std::string path = dir + "/anymal_small.bag";
  const YAML::Node rig = YAML::LoadFile(dir + "/rig.yaml");
  auto bag = openBag(path);
  for (int cam = 0; cam < 2; ++cam) {
    const YAML::Node c = rig["cameras"][cam];
    const auto in = c["intrinsics"].as<std::vector<double>>();
    const auto dist = c["distortion_coeffs"].as<std::vector<double>>();
    const std::string name = "cam" + std::to_string(cam);
    std::vector<std::int64_t> info_stamps, image_stamps;
    bag->read({"/" + name + "/camera_info"}, [&](const RawMessage& m) {
      const CameraInfo ci = decodeCameraInfo(m, path);
      info_stamps.push_back(ci.header.stamp_ns);
      CHECK(ci.header.frame_id == name + "_optical_frame");
      CHECK(ci.width == 640);
      CHECK(ci.height == 480);
      CHECK(ci.distortion_model == "plumb_bob");
      CHECK(ci.d == std::vector<double>{dist[0], dist[1], dist[2], dist[3], 0.0});
      CHECK(ci.k == std::array<double, 9>{in[0], 0, in[2], 0, in[1], in[3], 0, 0, 1});
      CHECK(ci.r == std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1});
      CHECK(ci.p == std::array<double, 12>{in[0], 0, in[2], 0, 0, in[1], in[3], 0, 0, 0, 1, 0});
      CHECK(ci.binning_x == 0);
      CHECK(ci.binning_y == 0);
      return true;
    });
    bag->read({cam == 0 ? "/cam0/image_raw" : "/cam1/image_raw/compressed"}, [&](const RawMessage& m) {
      image_stamps.push_back(decodeHeaderStamp(m, path));
      return true;
    });
    CHECK(info_stamps.size() == 40);
    std::sort(info_stamps.begin(), info_stamps.end());
    std::sort(image_stamps.begin(), image_stamps.end());
    CHECK(info_stamps == image_stamps);
  }
}

TEST_CASE("ANYmal bag: the same messages and topics through the index and through a linear scan",
          "[logs][ros1]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  TempDir tmp;
  const std::string killed = tmp / "killed.bag";
  writeBytes(killed, unindexedCopy(readFile(dir + "/anymal_small.bag")));
  auto indexed = openBag(dir + "/anymal_small.bag");
  auto scanned = openBag(killed);
  CHECK(scanned->format().find("no index") != std::string::npos);
  REQUIRE(scanned->topics().size() == indexed->topics().size());
  for (std::size_t i = 0; i < indexed->topics().size(); ++i) {
    const TopicInfo &a = indexed->topics()[i], &b = scanned->topics()[i];
    CHECK(a.name == b.name);
    CHECK(a.type == b.type);
    CHECK(a.definition == b.definition);
    CHECK(a.message_count == b.message_count);
    CHECK(a.first_record_ns == b.first_record_ns);
    CHECK(a.last_record_ns == b.last_record_ns);
  }
  const auto all = readAll(*indexed);
  CHECK(all.size() == 4281);
  CHECK(all == readAll(*scanned));
  // A subset skips chunks without its topics but keeps the per-topic numbering.
  std::vector<Seen> infos;
  for (const auto& s : all)
    if (s.topic == "/cam1/camera_info") infos.push_back(s);
  CHECK(readAll(*indexed, {"/cam1/camera_info"}) == infos);
  CHECK(readAll(*scanned, {"/cam1/camera_info"}) == infos);
}

TEST_CASE("ANYmal bag: reading every message streams one chunk at a time (timed)", "[logs][ros1][timing]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const auto t0 = std::chrono::steady_clock::now();
  auto bag = openBag(dir + "/anymal_small.bag");
  const auto t1 = std::chrono::steady_clock::now();
  std::size_t n = 0, bytes = 0, largest = 0;
  bag->read({}, [&](const RawMessage& m) {
    ++n, bytes += m.size, largest = std::max(largest, m.size);
    return true;
  });
  const auto t2 = std::chrono::steady_clock::now();
  const auto ms = [](auto d) { return std::chrono::duration<double, std::milli>(d).count(); };
  WARN("anymal_small.bag: open " << ms(t1 - t0) << " ms, read " << n << " messages (" << bytes
                                 << " bytes) in " << ms(t2 - t1) << " ms");
  CHECK(n == 4281);
  CHECK(largest >= 307200);
}

// ---------------------------------------------------------------------------
// The small fixtures written by rosbag's Python writer

TEST_CASE("ROS 1 fixtures: none, bz2 and lz4 chunks decode to the same, known messages", "[logs][ros1]") {
  std::vector<Seen> reference;
  for (const std::string comp : {"none", "bz2", "lz4"}) {
    INFO("compression " << comp);
    const std::string path = kFixtures + "ros1_" + comp + ".bag";
    auto bag = openBag(path);
    CHECK(bag->format().find("compression " + comp) != std::string::npos);
    CHECK(bag->format().find("6 chunk(s)") != std::string::npos);
    REQUIRE(bag->topics().size() == 4);
    // Two connections (two publishers) on /joint_states make one topic.
    const TopicInfo* js_topic = bag->findTopic("/joint_states");
    REQUIRE(js_topic);
    CHECK(js_topic->message_count == 24);
    CHECK(js_topic->type == "sensor_msgs/JointState");
    CHECK(bag->findTopic("/cam0/camera_info")->message_count == 4);
    CHECK(bag->findTopic("/cam1/image_raw/compressed")->type == "sensor_msgs/CompressedImage");
    // the first compressed image recorded 6.5 ms after T0; the last camera info 2.5 ms after T0 + 305 ms
    CHECK(bag->startNs() == kT0 + 6500000);
    CHECK(bag->endNs() == kT0 + 307500000);
    bag->read({}, [&](const RawMessage& m) {
      switch (messageKind(m.topic->type)) {
        case MessageKind::JointState: {
          const JointState js = decodeJointState(m, path);
          const auto i = static_cast<double>((js.header.stamp_ns - kT0) / 10000000);
          CHECK(js.header.frame_id == "base");
          CHECK(js.name == std::vector<std::string>{"a", "b", "c"});
          CHECK(js.position == std::vector<double>{0.1 * i, -0.2 * i, 0.5 + 0.01 * i});
          if (static_cast<int>(i) % 2 == 0)
            CHECK(js.velocity == std::vector<double>{i, 0.0, -i});
          else
            CHECK(js.velocity.empty());
          CHECK(js.effort.empty());
          break;
        }
        case MessageKind::Image: {
          const Image im = decodeImage(m, path);
          const int n = static_cast<int>((im.header.stamp_ns - kT0 - 5000000) / 100000000);
          CHECK(im.header.stamp_ns == kT0 + 5000000 + n * std::int64_t{100000000});
          CHECK(im.header.frame_id == "cam0");
          CHECK(im.width == 4);
          CHECK(im.height == 3);
          CHECK(im.step == 4);
          CHECK(im.encoding == "mono8");
          REQUIRE(im.data.size() == 12);
          for (int k = 0; k < 12; ++k) CHECK(im.data[static_cast<std::size_t>(k)] == (17 * n + k) % 256);
          CHECK(m.index == static_cast<std::uint64_t>(n));
          break;
        }
        case MessageKind::CameraInfo: {
          const CameraInfo ci = decodeCameraInfo(m, path);
          const double n = static_cast<double>(m.index);
          CHECK(ci.header.stamp_ns == kT0 + 5000000 + static_cast<std::int64_t>(m.index) * 100000000);
          CHECK(ci.distortion_model == "plumb_bob");
          CHECK(ci.d == std::vector<double>{-0.25, 0.07, 0.001, -0.002, 0.0});
          CHECK(ci.k == std::array<double, 9>{400 + n, 0, 320, 0, 401, 240, 0, 0, 1});
          CHECK(ci.r == std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1});
          CHECK(ci.p == std::array<double, 12>{400 + n, 0, 320, 0, 0, 401, 240, 0, 0, 0, 1, 0});
          CHECK(ci.width == 4);
          CHECK(ci.height == 3);
          break;
        }
        case MessageKind::CompressedImage: {
          const CompressedImage ci = decodeCompressedImage(m, path);
          const auto n = static_cast<std::uint8_t>(m.index);
          std::vector<std::uint8_t> want = {0xff, 0xd8};
          want.insert(want.end(), n, n);
          want.insert(want.end(), {0xff, 0xd9});
          CHECK(ci.format == "jpeg");
          CHECK(ci.header.frame_id == "cam1");
          CHECK(ci.data == want);
          break;
        }
        case MessageKind::Other: FAIL("unexpected type " << m.topic->type);
      }
      return true;
    });
    const auto seen = readAll(*bag);
    CHECK(seen.size() == 36);
    if (reference.empty())
      reference = seen;
    else
      CHECK(seen == reference);
    // The unindexed copy reads the same.
    TempDir tmp;
    writeBytes(tmp / "killed.bag", unindexedCopy(readFile(path)));
    auto scanned = openBag(tmp / "killed.bag");
    CHECK(readAll(*scanned) == seen);
    CHECK(scanned->findTopic("/joint_states")->message_count == 24);
  }
  // Joint sample i + 1 (latency 2 ms) is recorded before sample i when i is a
  // multiple of 3 (latency 15 ms): the per-topic index follows the storage
  // order, not the stamps.
  auto bag = openBag(kFixtures + "ros1_lz4.bag");
  std::vector<std::int64_t> stamps;
  bag->read({"/joint_states"}, [&](const RawMessage& m) {
    CHECK(m.index == stamps.size());
    stamps.push_back(decodeHeaderStamp(m, kFixtures + "ros1_lz4.bag"));
    return true;
  });
  CHECK_FALSE(std::is_sorted(stamps.begin(), stamps.end()));
}

TEST_CASE("ROS 1 reader: read() stops when the callback returns false", "[logs][ros1]") {
  auto bag = openBag(kFixtures + "ros1_bz2.bag");
  int calls = 0;
  bag->read({}, [&](const RawMessage&) { return ++calls < 5; });
  CHECK(calls == 5);
}

// ---------------------------------------------------------------------------
// Damaged and hostile input: a LogError naming the file and the place

TEST_CASE("ROS 1 reader: a topic that is not in the bag is refused with the list of those that are",
          "[logs][ros1][errors]") {
  const std::string path = kFixtures + "ros1_none.bag";
  auto bag = openBag(path);
  const LogError e = errorOf([&] { bag->read({"/joint_states", "/cam2/image_raw"}, [](const RawMessage&) { return true; }); });
  CHECK(e.file() == path);
  CHECK(e.where() == "topic /cam2/image_raw");
  CHECK(std::string(e.what()).find("/cam0/camera_info, /cam0/image_raw, /cam1/image_raw/compressed, /joint_states") !=
        std::string::npos);
}

TEST_CASE("ROS 1 reader: a bag cut in the middle of a chunk, with or without its index", "[logs][ros1][errors]") {
  for (const std::string comp : {"none", "bz2", "lz4"}) {
    INFO(comp);
    const std::string bytes = readFile(kFixtures + "ros1_" + comp + ".bag");
    const auto chunks = chunksOf(bytes);
    REQUIRE(chunks.size() == 6);
    const Record& third = chunks[2];
    TempDir tmp;
    // Killed while writing: index_pos 0, file ends inside the third chunk.
    std::string killed = unindexedCopy(bytes);
    killed.resize(third.data_pos + third.data_len / 2);
    writeBytes(tmp / "killed.bag", killed);
    LogError e = errorOf([&] { openBag(tmp / "killed.bag"); });
    CHECK(e.file() == tmp / "killed.bag");
    CHECK(e.where() == "offset " + std::to_string(third.pos));
    CHECK(e.detail().find("remain in the file (the bag was cut short?)") != std::string::npos);
    // Closed, then cut: index_pos points past the end, so the bag is scanned.
    std::string cut = bytes;
    cut.resize(third.data_pos + 10);
    writeBytes(tmp / "cut.bag", cut);
    e = errorOf([&] { openBag(tmp / "cut.bag"); });
    CHECK(e.where() == "offset " + std::to_string(third.pos));
    CHECK(e.detail().find("declares " + std::to_string(third.data_len) + " data bytes but only 10 remain") !=
          std::string::npos);
    // Cut inside the record header of a chunk.
    cut.resize(third.pos + 6);
    writeBytes(tmp / "cut.bag", cut);
    e = errorOf([&] { openBag(tmp / "cut.bag"); });
    CHECK(e.where() == "offset " + std::to_string(third.pos));
  }
}

TEST_CASE("ROS 1 reader: an unknown chunk compression is named", "[logs][ros1][errors]") {
  std::string bytes = readFile(kFixtures + "ros1_lz4.bag");
  const auto chunks = chunksOf(bytes);
  const std::size_t at = chunks[1].field_value_pos.at("compression");
  REQUIRE(bytes.substr(at, 3) == "lz4");
  bytes.replace(at, 3, "xz7");
  TempDir tmp;
  writeBytes(tmp / "xz.bag", bytes);
  const LogError e = errorOf([&] { openBag(tmp / "xz.bag"); });
  CHECK(e.where() == "offset " + std::to_string(chunks[1].pos));
  CHECK(e.detail() == "chunk compression 'xz7' is not supported; expected none, bz2 or lz4");
  // The same without an index (found by the scan).
  writeBytes(tmp / "xz_killed.bag", unindexedCopy(bytes));
  CHECK(errorOf([&] { openBag(tmp / "xz_killed.bag"); }).detail() == e.detail());
}

TEST_CASE("ROS 1 reader: a record whose declared length runs past the file", "[logs][ros1][errors]") {
  std::string bytes = readFile(kFixtures + "ros1_bz2.bag");
  const auto chunks = chunksOf(bytes);
  putU32(bytes, chunks[0].data_pos - 4, 0x7ffffff0);  // the first chunk's data_len
  TempDir tmp;
  writeBytes(tmp / "long.bag", bytes);
  const LogError e = errorOf([&] { openBag(tmp / "long.bag"); });
  CHECK(e.file() == tmp / "long.bag");
  CHECK(e.where() == "offset " + std::to_string(chunks[0].pos));
  CHECK(e.detail().find("declares 2147483632 data bytes but only") != std::string::npos);
  // A header length past the end.
  bytes = readFile(kFixtures + "ros1_bz2.bag");
  putU32(bytes, chunks[3].pos, 0x00ffffff);
  writeBytes(tmp / "header.bag", bytes);
  const LogError h = errorOf([&] { openBag(tmp / "header.bag"); });
  CHECK(h.where() == "offset " + std::to_string(chunks[3].pos));
  CHECK(h.detail().find("record header declares 16777215 bytes but only") != std::string::npos);
}

TEST_CASE("ROS 1 reader: a chunk larger than max_chunk_bytes is refused from its declared size",
          "[logs][ros1][errors]") {
  const std::string path = kFixtures + "ros1_lz4.bag";
  const auto chunks = chunksOf(readFile(path));
  std::uint32_t largest = 0;
  for (const auto& c : chunks) largest = std::max(largest, getU32(c.fields.at("size"), 0));
  ReadLimits limits;
  limits.max_chunk_bytes = largest - 1;
  const LogError e = errorOf([&] { openBag(path, limits); });
  CHECK(e.file() == path);
  CHECK(e.where().rfind("offset ", 0) == 0);
  CHECK(e.detail().find("uncompressed bytes, more than the limit of " + std::to_string(largest - 1)) !=
        std::string::npos);
  limits.max_chunk_bytes = largest;
  CHECK_NOTHROW(readAndDecodeEverything(path, limits));

  // A declared size of 4 GiB - 1 is refused before anything is allocated.
  std::string bytes = readFile(path);
  putU32(bytes, chunks[0].field_value_pos.at("size"), 0xffffffff);
  TempDir tmp;
  writeBytes(tmp / "huge.bag", bytes);
  limits.max_chunk_bytes = 64 << 20;
  const LogError h = errorOf([&] { openBag(tmp / "huge.bag", limits); });
  CHECK(h.where() == "offset " + std::to_string(chunks[0].pos));
  CHECK(h.detail().find("declares 4294967295 uncompressed bytes") != std::string::npos);
}

TEST_CASE("ROS 1 reader: a chunk that decompresses to more or less than its declared size", "[logs][ros1][errors]") {
  for (const std::string comp : {"bz2", "lz4"}) {
    INFO(comp);
    std::string bytes = readFile(kFixtures + "ros1_" + comp + ".bag");
    const auto chunks = chunksOf(bytes);
    const std::uint32_t size = getU32(chunks[4].fields.at("size"), 0);
    putU32(bytes, chunks[4].field_value_pos.at("size"), size - 100);
    TempDir tmp;
    writeBytes(tmp / "small.bag", bytes);
    auto bag = openBag(tmp / "small.bag");  // the index is intact: the chunk is read by read()
    LogError e = errorOf([&] { readAll(*bag); });
    CHECK(e.where() == "offset " + std::to_string(chunks[4].pos));
    CHECK(e.detail().find("decompresses to more than its declared size of " + std::to_string(size - 100)) !=
          std::string::npos);
    putU32(bytes, chunks[4].field_value_pos.at("size"), size + 100);
    writeBytes(tmp / "large.bag", bytes);
    bag = openBag(tmp / "large.bag");
    e = errorOf([&] { readAll(*bag); });
    CHECK(e.where() == "offset " + std::to_string(chunks[4].pos));
    CHECK(e.detail().find("decompresses to " + std::to_string(size) + " bytes; its header declares " +
                          std::to_string(size + 100)) != std::string::npos);
    // Damaged compressed bytes.
    bytes = readFile(kFixtures + "ros1_" + comp + ".bag");
    for (std::size_t k = chunks[2].data_pos + 8; k < chunks[2].end() - 8; k += 7) bytes[k] = static_cast<char>(~bytes[k]);
    writeBytes(tmp / "damaged.bag", bytes);
    bag = openBag(tmp / "damaged.bag");
    e = errorOf([&] { readAll(*bag); });
    CHECK(e.where() == "offset " + std::to_string(chunks[2].pos));
  }
}

TEST_CASE("ROS 1 reader: garbage is a LogError, never a crash", "[logs][ros1][errors]") {
  TempDir tmp;
  const std::string good = readFile(kFixtures + "ros1_lz4.bag");
  // Not a bag at all / a bag of another version / a header with nothing after it.
  writeBytes(tmp / "zeros.bag", std::string(5000, '\0'));
  CHECK(errorOf([&] { openBag(tmp / "zeros.bag"); }).where() == "offset 0");
  writeBytes(tmp / "v12.bag", "#ROSBAG V1.2\n" + good.substr(13));
  CHECK(errorOf([&] { openBag(tmp / "v12.bag"); }).detail().find("expected #ROSBAG V2.0") != std::string::npos);
  writeBytes(tmp / "magic_only.bag", good.substr(0, 13));
  CHECK(errorOf([&] { openBag(tmp / "magic_only.bag"); }).where() == "offset 13");
  // The first record is not the bag header.
  const auto recs = topLevelRecords(good);
  std::string b = good;
  b[recs[0].field_value_pos.at("op")] = 0x05;
  writeBytes(tmp / "op.bag", b);
  CHECK(errorOf([&] { openBag(tmp / "op.bag"); }).detail().find("expected the bag header record") !=
        std::string::npos);
  // An encrypted bag (rosbag's encryptor plugins): a bag header field, the
  // header padding shortened to keep the first chunk where it was.
  {
    const Record& bh = recs[0];
    std::string fields = good.substr(bh.header_pos, bh.data_pos - 4 - bh.header_pos);
    const std::string extra = "encryptor=rosbag/AesCbcEncryptor";
    std::string len(4, '\0');
    putU32(len, 0, static_cast<std::uint32_t>(extra.size()));
    fields += len + extra;
    std::string rec(4, '\0');
    putU32(rec, 0, static_cast<std::uint32_t>(fields.size()));
    rec += fields;
    const std::size_t padding = bh.end() - bh.pos - rec.size() - 4;
    std::string dl(4, '\0');
    putU32(dl, 0, static_cast<std::uint32_t>(padding));
    rec += dl + std::string(padding, ' ');
    std::string enc = good;
    enc.replace(bh.pos, bh.end() - bh.pos, rec);
    REQUIRE(enc.size() == good.size());
    writeBytes(tmp / "encrypted.bag", enc);
    const LogError e = errorOf([&] { openBag(tmp / "encrypted.bag"); });
    CHECK(e.where() == "offset 13");
    CHECK(e.detail().find("the bag is encrypted (encryptor 'rosbag/AesCbcEncryptor')") == 0);
  }
  // Every cut of a fixture, and pseudo-random bytes after a valid start: each
  // either reads (a cut at a record boundary) or gives a LogError naming the file.
  std::uint32_t state = 12345;
  for (std::size_t cut = 13; cut < good.size(); cut += 211) {
    for (const bool killed : {false, true}) {
      std::string c = killed ? unindexedCopy(good) : good;
      if (cut >= c.size()) continue;
      c.resize(cut);
      writeBytes(tmp / "cut.bag", c);
      try {
        readAndDecodeEverything(tmp / "cut.bag");
      } catch (const LogError& e) {
        CHECK(e.file() == tmp / "cut.bag");
      }
    }
    std::string noisy = good;
    for (int k = 0; k < 8; ++k) {
      state = state * 1664525u + 1013904223u;
      noisy[cut + (state >> 8) % (good.size() - cut)] = static_cast<char>(state >> 24);
    }
    writeBytes(tmp / "noisy.bag", noisy);
    try {
      readAndDecodeEverything(tmp / "noisy.bag");
    } catch (const LogError& e) {
      CHECK(e.file() == tmp / "noisy.bag");
    }
  }
}

// ---------------------------------------------------------------------------
// The ROS 1 message decoders on damaged payloads

namespace {

/// The first message of `topic` in the lz4 fixture, as bytes.
std::string firstPayload(const std::string& topic) {
  auto bag = openBag(kFixtures + "ros1_lz4.bag");
  std::string out;
  bag->read({topic}, [&](const RawMessage& m) {
    out.assign(reinterpret_cast<const char*>(m.data), m.size);
    return false;
  });
  return out;
}

RawMessage rawOf(const TopicInfo& topic, const std::string& bytes, std::uint64_t index) {
  RawMessage m;
  m.topic = &topic;
  m.index = index;
  m.data = reinterpret_cast<const std::uint8_t*>(bytes.data());
  m.size = bytes.size();
  return m;
}

TopicInfo ros1Topic(const std::string& name, const std::string& type) {
  TopicInfo t;
  t.name = name;
  t.type = type;
  t.serialization = Serialization::Ros1;
  return t;
}

}  // namespace

TEST_CASE("ROS 1 decoders: every truncation of a message names the topic, the message and the field",
          "[logs][ros1][errors]") {
  const TopicInfo js = ros1Topic("/joint_states", "sensor_msgs/JointState");
  const TopicInfo im = ros1Topic("/cam0/image_raw", "sensor_msgs/Image");
  const TopicInfo ci = ros1Topic("/cam0/camera_info", "sensor_msgs/CameraInfo");
  const TopicInfo cc = ros1Topic("/cam1/image_raw/compressed", "sensor_msgs/CompressedImage");
  const std::vector<std::pair<const TopicInfo*, std::string>> cases = {
      {&js, firstPayload("/joint_states")},
      {&im, firstPayload("/cam0/image_raw")},
      {&ci, firstPayload("/cam0/camera_info")},
      {&cc, firstPayload("/cam1/image_raw/compressed")}};
  for (const auto& [topic, full] : cases) {
    INFO(topic->name);
    REQUIRE(full.size() > 20);
    for (std::size_t n = 0; n < full.size(); ++n) {
      const std::string part = full.substr(0, n);
      const RawMessage m = rawOf(*topic, part, 7);
      const LogError e = errorOf([&] {
        switch (messageKind(topic->type)) {
          case MessageKind::JointState: decodeJointState(m, "f.bag"); break;
          case MessageKind::Image: decodeImage(m, "f.bag"); break;
          case MessageKind::CameraInfo: decodeCameraInfo(m, "f.bag"); break;
          default: decodeCompressedImage(m, "f.bag"); break;
        }
      });
      CHECK(e.file() == "f.bag");
      CHECK(e.where() == "topic " + topic->name + ", message 7");
      CHECK(e.detail().find("field ") == 0);
    }
    // One byte too many.
    const std::string longer = full + "x";
    const LogError e = errorOf([&] {
      const RawMessage m = rawOf(*topic, longer, 3);
      switch (messageKind(topic->type)) {
        case MessageKind::JointState: decodeJointState(m, "f.bag"); break;
        case MessageKind::Image: decodeImage(m, "f.bag"); break;
        case MessageKind::CameraInfo: decodeCameraInfo(m, "f.bag"); break;
        default: decodeCompressedImage(m, "f.bag"); break;
      }
    });
    CHECK(e.detail().find("1 byte(s) left over") == 0);
  }
}

TEST_CASE("ROS 1 decoders: lengths past the end, nsec >= 1e9 and a wrong type are LogErrors",
          "[logs][ros1][errors]") {
  const TopicInfo js = ros1Topic("/joint_states", "sensor_msgs/JointState");
  std::string msg = firstPayload("/joint_states");
  // header: seq(4) sec(4) nsec(4) frame_id(4 + 4 "base"), then name[] count at 20.
  REQUIRE(getU32(msg, 12) == 4);
  REQUIRE(getU32(msg, 20) == 3);
  std::string bad = msg;
  putU32(bad, 20, 0x40000000);  // a billion names
  LogError e = errorOf([&] { decodeJointState(rawOf(js, bad, 2), "f.bag"); });
  CHECK(e.where() == "topic /joint_states, message 2");
  CHECK(e.detail().find("field name needs array of 1073741824 strings") == 0);
  bad = msg;
  putU32(bad, 24, 0xfffffff0);  // the first name's length
  e = errorOf([&] { decodeJointState(rawOf(js, bad, 2), "f.bag"); });
  CHECK(e.detail().find("field name needs string of 4294967280 bytes") == 0);
  bad = msg;
  putU32(bad, 8, 1000000000);
  e = errorOf([&] { decodeHeaderStamp(rawOf(js, bad, 5), "f.bag"); });
  CHECK(e.where() == "topic /joint_states, message 5");
  CHECK(e.detail() == "field header.stamp.nsec: expected less than 1000000000, found 1000000000");
  CHECK_THROWS_AS(decodeJointState(rawOf(js, bad, 5), "f.bag"), LogError);
  // decodeHeaderStamp reads only the header: the rest may be anything.
  putU32(msg, 8, 999999999);
  const std::string header_only = msg.substr(0, 20) + "garbage";
  CHECK(decodeHeaderStamp(rawOf(js, header_only, 0), "f.bag") == std::int64_t{getU32(msg, 4)} * 1000000000 + 999999999);
  // A JointState topic is not an Image.
  e = errorOf([&] { decodeImage(rawOf(js, msg, 0), "f.bag"); });
  CHECK(e.detail().find("expected messages of type sensor_msgs/Image") == 0);
  // No data at all.
  RawMessage empty = rawOf(js, "", 0);
  empty.data = nullptr;
  CHECK_THROWS_AS(decodeHeaderStamp(empty, "f.bag"), LogError);
}

// The ROS 1 and CDR decoders are one decoding per type: a bool that is
// neither 0 nor 1 is refused in ROS 1 as CDR refuses it (test_logs_mcap.cpp),
// rather than read as true.
TEST_CASE("ROS 1 decoders: is_bigendian and roi.do_rectify above 1 are refused, naming the field and the value",
          "[logs][ros1][errors]") {
  const TopicInfo im = ros1Topic("/cam0/image_raw", "sensor_msgs/Image");
  const TopicInfo ci = ros1Topic("/cam0/camera_info", "sensor_msgs/CameraInfo");
  SECTION("Image.is_bigendian") {
    std::string bad = firstPayload("/cam0/image_raw");
    // header: seq sec nsec frame_id; then height, width, encoding, is_bigendian
    const std::size_t after_header = 16 + getU32(bad, 12);
    const std::size_t encoding = after_header + 8;
    const std::size_t flag = encoding + 4 + getU32(bad, encoding);
    REQUIRE(bad.at(flag) == 0);
    bad[flag] = 2;
    const LogError e = errorOf([&] { decodeImage(rawOf(im, bad, 4), "f.bag"); });
    CHECK(e.file() == "f.bag");
    CHECK(e.where() == "topic /cam0/image_raw, message 4");
    CHECK(e.detail() == "field is_bigendian: expected a bool (0 or 1), found 2");
    bad[flag] = 1;  // 1 is a bool: the image says big-endian
    CHECK(decodeImage(rawOf(im, bad, 4), "f.bag").is_bigendian);
  }
  SECTION("CameraInfo.roi.do_rectify, the message's last byte") {
    std::string bad = firstPayload("/cam0/camera_info");
    REQUIRE(bad.back() == 1);  // the fixture sets do_rectify
    bad.back() = 2;
    const LogError e = errorOf([&] { decodeCameraInfo(rawOf(ci, bad, 6), "f.bag"); });
    CHECK(e.where() == "topic /cam0/camera_info, message 6");
    CHECK(e.detail() == "field roi.do_rectify: expected a bool (0 or 1), found 2");
  }
}
