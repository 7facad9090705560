// The rosbag2 sqlite3 reader (one .db3) and the rosbag2 folder reader
// (metadata.yaml, split bags, folders without metadata.yaml) on the shared
// fixtures: the Jazzy and Humble layouts of the anymal_small capture and the
// bags rosbag2's own tests wrote. Split bags and damaged files are made here,
// at test time, by editing copies of those real files with libsqlite3 (the
// fixtures are read-only), never by writing a bag format of our own.
#include <sqlite3.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <unistd.h>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fgcal_test/files.hpp"
#include "fgcal_test/sha256.hpp"
#include "fgcal_test/shared_data.hpp"

namespace fs = std::filesystem;
using namespace fgcal::logs;

namespace {

// --- helpers ---------------------------------------------------------------

class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    path_ = fs::temp_directory_path() / ("fgcal_logs_sqlite_" + std::to_string(::getpid()) + "_" +
                                         std::to_string(counter++) + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& sub) const { return (path_ / sub).string(); }
  std::string str() const { return path_.string(); }

 private:
  fs::path path_;
};

void writeFile(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

/// Copies a fixture (read-only) to `to`, writable.
void copyFixture(const std::string& from, const std::string& to) {
  fs::create_directories(fs::path(to).parent_path());
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
  fs::permissions(to, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
}

/// Runs SQL on a (copied) db3 with libsqlite3, as a user editing a bag would.
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

using fgcal::test::sha256Hex;

/// One delivered message, enough to compare two readings.
struct Seen {
  std::string topic;
  std::int64_t record_ns;
  std::uint64_t index;
  std::size_t size;
  std::uint64_t fnv;
  bool operator==(const Seen& o) const {
    return topic == o.topic && record_ns == o.record_ns && index == o.index && size == o.size && fnv == o.fnv;
  }
};

std::uint64_t fnv1a(const std::uint8_t* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

std::vector<Seen> readAll(BagReader& bag, const std::vector<std::string>& topics = {}) {
  std::vector<Seen> out;
  bag.read(topics, [&](const RawMessage& m) {
    out.push_back({m.topic->name, m.record_ns, m.index, m.size, fnv1a(m.data, m.size)});
    return true;
  });
  return out;
}

/// The text of the LogError a call throws ("" when it throws none).
template <class F>
std::string logError(F&& f) {
  try {
    f();
  } catch (const LogError& e) {
    return e.what();
  }
  return "";
}

std::string anymal(const std::string& sub) { return "bags/anymal_small/" + sub; }

// The Jazzy bag's topics as its db3 holds them (README.md, and SQL COUNT/MIN/MAX).
struct ExpectedTopic {
  const char* name;
  const char* type;
  std::uint64_t count;
  std::int64_t first, last;
};
const ExpectedTopic kJazzy[] = {
    {"/cam0/camera_info", "sensor_msgs/msg/CameraInfo", 40, 1700877874274135099, 1700877894271405544},
    {"/cam0/image_raw", "sensor_msgs/msg/Image", 40, 1700877874273865923, 1700877894271577926},
    {"/cam1/camera_info", "sensor_msgs/msg/CameraInfo", 40, 1700877874272482141, 1700877894268958176},
    {"/cam1/image_raw/compressed", "sensor_msgs/msg/CompressedImage", 40, 1700877874270455463, 1700877894275480269},
    {"/joint_states", "sensor_msgs/msg/JointState", 4121, 1700877873973775615, 1700877894572002932},
};

void checkJazzyTopics(const BagReader& bag) {
  const auto& topics = bag.topics();
  REQUIRE(topics.size() == 5);
  for (std::size_t i = 0; i < 5; ++i) {
    INFO(kJazzy[i].name);
    CHECK(topics[i].name == kJazzy[i].name);
    CHECK(topics[i].type == kJazzy[i].type);
    CHECK(topics[i].serialization == Serialization::Cdr);
    CHECK(topics[i].message_count == kJazzy[i].count);
    CHECK(topics[i].first_record_ns == kJazzy[i].first);
    CHECK(topics[i].last_record_ns == kJazzy[i].last);
    // The full definition text ros2 bag record stores, dependencies included.
    CHECK(topics[i].definition.find("MSG: std_msgs/Header") != std::string::npos);
  }
  // starting_time and starting_time + duration of metadata.yaml.
  CHECK(bag.startNs() == 1700877873973775615);
  CHECK(bag.endNs() == 1700877873973775615 + 20598227317);
}

struct ExpectedImage {
  std::string topic;
  std::int64_t stamp_ns, record_ns;
  std::uint32_t width, height, step;
  std::string encoding_or_format;
  std::size_t bytes;
  std::string sha;
};

std::vector<ExpectedImage> expectedImages(const std::string& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<ExpectedImage> out;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) f.push_back(c);
    REQUIRE(f.size() == 10);
    // width, height and step are empty for CompressedImage; the format is quoted.
    auto u32 = [](const std::string& v) { return v.empty() ? 0u : static_cast<std::uint32_t>(std::stoul(v)); };
    std::string fmt = f[7];
    if (fmt.size() >= 2 && fmt.front() == '"' && fmt.back() == '"') fmt = fmt.substr(1, fmt.size() - 2);
    out.push_back({f[1], std::stoll(f[2]), std::stoll(f[3]), u32(f[4]), u32(f[5]), u32(f[6]), fmt, std::stoul(f[8]), f[9]});
  }
  return out;
}

/// The split bag of the tests: the Jazzy db3 cut at record time `mid` into two
/// files; the first file also loses /cam1/camera_info entirely (topic row and
/// messages), as a topic that starts publishing in a later file does.
const std::int64_t kMid = 1700877884000000000;

void makeSplitFiles(const std::string& jazzy_db3, const std::string& first, const std::string& second) {
  copyFixture(jazzy_db3, first);
  copyFixture(jazzy_db3, second);
  execSql(first,
          "DELETE FROM messages WHERE timestamp >= " + std::to_string(kMid) +
              ";"
              "DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '/cam1/camera_info');"
              "DELETE FROM topics WHERE name = '/cam1/camera_info';");
  execSql(second, "DELETE FROM messages WHERE timestamp < " + std::to_string(kMid) + ";");
}

std::string metadataYaml(int version, const std::vector<std::string>& files, std::uint64_t total,
                         const std::vector<std::pair<std::string, std::uint64_t>>& topic_counts,
                         const std::string& type_of_joint_states = "sensor_msgs/msg/JointState") {
  std::string y = "rosbag2_bagfile_information:\n  version: " + std::to_string(version) +
                  "\n  storage_identifier: sqlite3\n  duration:\n    nanoseconds: 1\n"
                  "  starting_time:\n    nanoseconds_since_epoch: 1\n  message_count: " +
                  std::to_string(total) + "\n  topics_with_message_count:\n";
  for (const auto& [name, count] : topic_counts) {
    std::string type = name == "/joint_states" ? type_of_joint_states
                       : name.find("camera_info") != std::string::npos ? "sensor_msgs/msg/CameraInfo"
                       : name.find("compressed") != std::string::npos  ? "sensor_msgs/msg/CompressedImage"
                                                                       : "sensor_msgs/msg/Image";
    y += "    - topic_metadata:\n        name: " + name + "\n        type: " + type +
         "\n        serialization_format: cdr\n        offered_qos_profiles: \"\"\n      message_count: " +
         std::to_string(count) + "\n";
  }
  y += "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n";
  for (const auto& f : files) y += "    - " + f + "\n";
  return y;
}

}  // namespace

// --- the real fixtures -------------------------------------------------------

TEST_CASE("sqlite: the Jazzy db3 folder lists its 5 topics with rosbag2's counts and times", "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_db3"));
  const auto bag = openBag(dir);
  CHECK(bag->path() == dir);
  CHECK(bag->format().find("rosbag2 sqlite3 (schema 4, jazzy)") != std::string::npos);
  CHECK(bag->format().find("1 file, metadata version 9") != std::string::npos);
  CHECK(bag->format().find("WARNING") == std::string::npos);
  checkJazzyTopics(*bag);
  // The same file opened alone.
  const auto file = openBag(dir + "/anymal_small_db3_0.db3");
  CHECK(file->format() == "rosbag2 sqlite3 (schema 4, jazzy)");
  checkJazzyTopics(*file);
}

TEST_CASE("sqlite: every message of the Jazzy db3 in record-time order, images equal expected_images.csv",
          "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_db3"));
  FGCAL_REQUIRE_SHARED_DATA(csv, anymal("expected_images.csv"));
  const auto expected = expectedImages(csv);
  REQUIRE(expected.size() == 80);
  const auto bag = openBag(dir);
  std::map<std::string, std::uint64_t> next;
  std::int64_t last = 0;
  std::size_t total = 0, image = 0, bad_head = 0, out_of_order = 0, bad_index = 0;
  std::vector<std::string> mismatches;
  {
    // The time to stream every message (touching each byte), for the record.
    std::uint64_t sum = 0;
    const auto t0 = std::chrono::steady_clock::now();
    bag->read({}, [&](const RawMessage& m) {
      for (std::size_t i = 0; i < m.size; ++i) sum += m.data[i];
      return true;
    });
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    WARN("reading all 4281 messages of the Jazzy db3 (15.3 MB) took " << ms << " ms (byte sum " << sum << ")");
  }
  bag->read({}, [&](const RawMessage& m) {
    ++total;
    if (m.record_ns < last) ++out_of_order;
    last = m.record_ns;
    if (m.index != next[m.topic->name]++) ++bad_index;
    // Little-endian CDR encapsulation header.
    if (m.size < 4 || m.data[0] != 0 || m.data[1] != 1 || m.data[2] != 0 || m.data[3] != 0) ++bad_head;
    if (m.topic->type == "sensor_msgs/msg/Image" || m.topic->type == "sensor_msgs/msg/CompressedImage") {
      // The pixel / JPEG bytes are the last field of both types: the blob's tail.
      // expected_images.csv lists camera by camera, each in record-time order.
      ++image;
      const auto e = std::find_if(expected.begin(), expected.end(), [&](const ExpectedImage& x) {
        return x.topic == m.topic->name && x.record_ns == m.record_ns;
      });
      const bool same = e != expected.end() && m.size >= e->bytes && sha256Hex(m.data + (m.size - e->bytes), e->bytes) == e->sha;
      if (!same) mismatches.push_back(m.topic->name + " #" + std::to_string(m.index));
    }
    return true;
  });
  CHECK(total == 4281);
  CHECK(image == 80);
  CHECK(out_of_order == 0);
  CHECK(bad_index == 0);
  CHECK(bad_head == 0);
  CHECK(mismatches.empty());
  for (const auto& t : kJazzy) CHECK(next[t.name] == t.count);
}

TEST_CASE("sqlite: the Jazzy db3's messages decode to the capture README.md describes", "[logs][sqlite][cdr]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_db3"));
  FGCAL_REQUIRE_SHARED_DATA(csv, anymal("expected_images.csv"));
  const auto expected = expectedImages(csv);
  const auto bag = openBag(dir);
  std::size_t images = 0, infos = 0, joints = 0;
  std::vector<std::string> mismatches;
  JointState first, last;
  first.header.stamp_ns = INT64_MAX;
  last.header.stamp_ns = INT64_MIN;
  std::map<std::string, std::vector<std::int64_t>> stamps;  // topic -> header stamps
  bag->read({}, [&](const RawMessage& m) {
    const std::string at = m.topic->name + " #" + std::to_string(m.index);
    const std::int64_t stamp = decodeHeaderStamp(m, dir);
    stamps[m.topic->name].push_back(stamp);
    switch (messageKind(m.topic->type)) {
      case MessageKind::Image:
      case MessageKind::CompressedImage: {
        ++images;
        const auto e = std::find_if(expected.begin(), expected.end(), [&](const ExpectedImage& x) {
          return x.topic == m.topic->name && x.record_ns == m.record_ns;
        });
        if (e == expected.end()) {
          mismatches.push_back(at + ": not in expected_images.csv");
          break;
        }
        std::vector<std::uint8_t> data;
        std::int64_t header = 0;
        bool fields = true;
        if (messageKind(m.topic->type) == MessageKind::Image) {
          const Image im = decodeImage(m, dir);
          data = im.data, header = im.header.stamp_ns;
          fields = im.width == e->width && im.height == e->height && im.step == e->step &&
                   im.encoding == e->encoding_or_format && im.header.frame_id == "cam0_optical_frame";
        } else {
          const CompressedImage ci = decodeCompressedImage(m, dir);
          data = ci.data, header = ci.header.stamp_ns;
          fields = ci.format == "mono8; jpeg compressed " && ci.format == e->encoding_or_format &&
                   ci.header.frame_id == "cam1_optical_frame";
        }
        if (!fields || header != e->stamp_ns || stamp != header || data.size() != e->bytes ||
            sha256Hex(data.data(), data.size()) != e->sha)
          mismatches.push_back(at);
        break;
      }
      case MessageKind::CameraInfo: {
        ++infos;
        const CameraInfo ci = decodeCameraInfo(m, dir);
        if (ci.width != 640 || ci.height != 480 || ci.distortion_model != "plumb_bob" || ci.d.size() != 5 ||
            ci.k[8] != 1.0 || ci.header.stamp_ns != stamp)
          mismatches.push_back(at);
        break;
      }
      case MessageKind::JointState: {
        ++joints;
        JointState js = decodeJointState(m, dir);
        if (js.name.size() != 12 || js.position.size() != 12 || !js.velocity.empty() || js.name[0] != "LF_HAA")
          mismatches.push_back(at);
        if (js.header.stamp_ns < first.header.stamp_ns) first = js;
        if (js.header.stamp_ns > last.header.stamp_ns) last = std::move(js);
        break;
      }
      case MessageKind::Other: mismatches.push_back(at + ": unexpected type"); break;
    }
    return true;
  });
  CHECK(mismatches.empty());
  CHECK(images == 80);
  CHECK(infos == 80);
  CHECK(joints == 4121);
  CHECK(first.header.stamp_ns == 1700877873968399947);
  CHECK(last.header.stamp_ns == 1700877894568399947);
  CHECK(first.position[0] == Approx(-0.0864595).margin(5e-8));
  CHECK(first.position[2] == Approx(-1.4634263).margin(5e-8));
  CHECK(last.position[1] == Approx(-0.3466659).margin(5e-8));
  const auto& cam0 = stamps["/cam0/image_raw"];
  CHECK(*std::min_element(cam0.begin(), cam0.end()) == 1700877874268399947);
  CHECK(*std::max_element(cam0.begin(), cam0.end()) == 1700877894267864430);
  // Each CameraInfo carries its image's stamp; both cameras are synchronised.
  for (const char* t : {"/cam0/camera_info", "/cam1/camera_info", "/cam1/image_raw/compressed"}) {
    auto a = stamps[t], b = cam0;
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    CHECK(a == b);
  }
  // Storage (record-time) order is not header-stamp order (README: 223 adjacent swaps).
  std::size_t swaps = 0;
  std::vector<std::int64_t> order;
  bag->read({}, [&](const RawMessage& m) {
    order.push_back(decodeHeaderStamp(m, dir));
    return true;
  });
  for (std::size_t i = 1; i < order.size(); ++i) swaps += order[i] < order[i - 1];
  CHECK(swaps == 223);
}

TEST_CASE("sqlite: the Humble cut decodes without stored definitions", "[logs][sqlite][cdr]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_humble_db3"));
  const auto bag = openBag(dir);
  std::size_t decoded = 0;
  bag->read({"/cam0/image_raw", "/cam1/image_raw/compressed", "/joint_states"}, [&](const RawMessage& m) {
    if (m.topic->name == "/joint_states") {
      CHECK(decodeJointState(m, dir).position.size() == 12);
    } else if (m.topic->name == "/cam0/image_raw") {
      CHECK(decodeImage(m, dir).data.size() == 640u * 480u);
    } else {
      CHECK(decodeCompressedImage(m, dir).data.size() > 1000);
    }
    ++decoded;
    return true;
  });
  CHECK(decoded == 270);
}

TEST_CASE("sqlite: the same capture as db3 folder and as MCAP file reads message for message alike",
          "[logs][sqlite][mcap]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_db3"));
  FGCAL_REQUIRE_SHARED_DATA(mcap, anymal("anymal_small.mcap"));
  const auto db3 = openBag(dir);
  const auto other = openBag(mcap);
  REQUIRE(other->topics().size() == db3->topics().size());
  for (std::size_t i = 0; i < db3->topics().size(); ++i) {
    CHECK(other->topics()[i].name == db3->topics()[i].name);
    CHECK(other->topics()[i].type == db3->topics()[i].type);
    CHECK(other->topics()[i].message_count == db3->topics()[i].message_count);
    CHECK(other->topics()[i].first_record_ns == db3->topics()[i].first_record_ns);
    CHECK(other->topics()[i].last_record_ns == db3->topics()[i].last_record_ns);
  }
  CHECK(readAll(*other) == readAll(*db3));

  // The MCAP file in a folder without metadata.yaml; then with a metadata.yaml
  // whose storage_identifier contradicts the file's extension.
  TempDir tmp;
  fs::create_directories(tmp / "bag");
  fs::copy_file(mcap, tmp / "bag/run_0.mcap");
  const auto folder = openBag(tmp / "bag");
  CHECK(folder->format().find("1 file, no metadata.yaml") != std::string::npos);
  CHECK(readAll(*folder) == readAll(*db3));
  writeFile(tmp / "bag/metadata.yaml", metadataYaml(9, {"run_0.mcap"}, 4281, {}));
  CHECK(logError([&] { openBag(tmp / "bag"); }) ==
        (tmp / "bag/metadata.yaml") +
            ": rosbag2_bagfile_information.storage_identifier: is 'sqlite3', but the storage file run_0.mcap is mcap");
}

TEST_CASE("sqlite: rosbag2's MCAP bag folders open through the folder reader", "[logs][sqlite][mcap][folder]") {
  FGCAL_REQUIRE_SHARED_DATA(res, "bags/rosbag2_tests/resources");
  for (const char* name : {"cdr_test", "bag_with_topics_and_service_events"}) {
    INFO(name);
    const auto mcap = openBag(res + "/mcap/" + name);
    const auto sqlite = openBag(res + "/sqlite3/" + name);
    CHECK(mcap->format().find("metadata version") != std::string::npos);
    CHECK(mcap->format().find("WARNING") == std::string::npos);
    REQUIRE(mcap->topics().size() == sqlite->topics().size());
    for (std::size_t i = 0; i < mcap->topics().size(); ++i) {
      CHECK(mcap->topics()[i].name == sqlite->topics()[i].name);
      CHECK(mcap->topics()[i].type == sqlite->topics()[i].type);
      CHECK(mcap->topics()[i].message_count == sqlite->topics()[i].message_count);
    }
    // cdr_test is one recording stored twice; the service-event bags are two recordings.
    if (std::string(name) == "cdr_test") CHECK(readAll(*mcap) == readAll(*sqlite));
    CHECK(readAll(*mcap).size() == readAll(*sqlite).size());
  }
}

TEST_CASE("sqlite: reading some topics, and stopping early", "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(db3, anymal("anymal_small_db3/anymal_small_db3_0.db3"));
  const auto bag = openBag(db3);
  const auto all = readAll(*bag);
  const auto cams = readAll(*bag, {"/cam1/camera_info", "/cam0/image_raw"});
  std::vector<Seen> want;
  for (const auto& s : all)
    if (s.topic == "/cam1/camera_info" || s.topic == "/cam0/image_raw") want.push_back(s);
  CHECK(cams.size() == 80);
  CHECK(cams == want);  // same order, same per-topic indexes as in the full reading
  std::size_t n = 0;
  bag->read({"/joint_states"}, [&](const RawMessage&) { return ++n < 10; });
  CHECK(n == 10);
}

TEST_CASE("sqlite: the Humble layout (schema 3, no message_definitions, metadata v5) opens", "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_humble_db3"));
  const auto bag = openBag(dir);
  CHECK(bag->format().find("rosbag2 sqlite3 (schema 3, humble)") != std::string::npos);
  CHECK(bag->format().find("metadata version 5") != std::string::npos);
  CHECK(bag->format().find("WARNING") == std::string::npos);
  REQUIRE(bag->topics().size() == 5);
  for (const auto& t : bag->topics()) {
    INFO(t.name);
    CHECK(t.definition.empty());  // Humble stores none
    CHECK(t.message_count == (t.name == "/joint_states" ? 264u : 3u));
  }
  const auto seen = readAll(*bag);
  CHECK(seen.size() == 264 + 4 * 3);
  CHECK(bag->findTopic("/cam0/image_raw")->first_record_ns == 1700877874273865923);
  CHECK(bag->findTopic("/joint_states")->last_record_ns == 1700877875289448682);
}

TEST_CASE("sqlite: the bags rosbag2's tests wrote list the topics and counts of their metadata.yaml",
          "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(res, "bags/rosbag2_tests/resources/sqlite3");
  {
    const auto bag = openBag(res + "/cdr_test");
    INFO(bag->format());
    CHECK(bag->format().find("schema 4, rolling") != std::string::npos);
    CHECK(bag->format().find("metadata version 7") != std::string::npos);
    CHECK(bag->format().find("WARNING") == std::string::npos);
    REQUIRE(bag->topics().size() == 2);
    CHECK(bag->topics()[0].name == "/array_topic");
    CHECK(bag->topics()[0].type == "test_msgs/msg/Arrays");
    CHECK(bag->topics()[0].message_count == 4);
    CHECK(bag->topics()[1].name == "/test_topic");
    CHECK(bag->topics()[1].type == "test_msgs/msg/BasicTypes");
    CHECK(bag->topics()[1].message_count == 3);
    CHECK(bag->startNs() == 1586406456763032325);
    CHECK(bag->endNs() == 1586406456763032325 + 151137181);
    CHECK(readAll(*bag).size() == 7);
  }
  {
    const auto bag = openBag(res + "/bag_with_topics_and_service_events");
    INFO(bag->format());
    CHECK(bag->format().find("rosbag2 sqlite3 (schema 4)") != std::string::npos);  // empty ros_distro
    CHECK(bag->format().find("metadata version 8") != std::string::npos);
    CHECK(bag->format().find("WARNING") == std::string::npos);
    const std::vector<std::pair<std::string, std::uint64_t>> want = {{"/events/write_split", 0},
                                                                     {"/test_service1/_service_event", 4},
                                                                     {"/test_service2/_service_event", 4},
                                                                     {"/test_topic1", 1},
                                                                     {"/test_topic2", 1}};
    REQUIRE(bag->topics().size() == want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
      CHECK(bag->topics()[i].name == want[i].first);
      CHECK(bag->topics()[i].message_count == want[i].second);
    }
    const TopicInfo* empty = bag->findTopic("/events/write_split");
    CHECK(empty->first_record_ns == 0);
    CHECK(empty->last_record_ns == 0);
    // A service event's definition is its service's .srv text (request --- response).
    const TopicInfo* event = bag->findTopic("/test_service1/_service_event");
    CHECK(event->type == "test_msgs/srv/BasicTypes_Event");
    CHECK(event->definition.find("---") != std::string::npos);
    CHECK(readAll(*bag).size() == 10);
    CHECK(readAll(*bag, {"/events/write_split"}).empty());
  }
}

// --- split bags and folders --------------------------------------------------

TEST_CASE("sqlite: a split bag (metadata.yaml with two db3 files) reads as one, indexes continuing",
          "[logs][sqlite][folder]") {
  FGCAL_REQUIRE_SHARED_DATA(db3, anymal("anymal_small_db3/anymal_small_db3_0.db3"));
  const auto whole = openBag(db3);
  const auto all = readAll(*whole);
  // What the split bag must deliver: everything but /cam1/camera_info before kMid.
  std::vector<Seen> want;
  std::uint64_t cam1_info = 0;
  for (auto s : all) {
    if (s.topic == "/cam1/camera_info") {
      if (s.record_ns < kMid) continue;
      s.index = cam1_info++;
    }
    want.push_back(s);
  }

  TempDir tmp;
  makeSplitFiles(db3, tmp / "split/split_0.db3", tmp / "split/split_1.db3");
  std::vector<std::pair<std::string, std::uint64_t>> counts;
  for (const auto& t : kJazzy) counts.emplace_back(t.name, t.name == std::string("/cam1/camera_info") ? cam1_info : t.count);
  writeFile(tmp / "split/metadata.yaml", metadataYaml(6, {"split_0.db3", "split_1.db3"}, want.size(), counts));

  const auto bag = openBag(tmp / "split");
  INFO(bag->format());
  CHECK(bag->format().find("2 files, metadata version 6") != std::string::npos);
  CHECK(bag->format().find("WARNING") == std::string::npos);
  REQUIRE(bag->topics().size() == 5);
  for (std::size_t i = 0; i < 5; ++i) {
    CHECK(bag->topics()[i].name == kJazzy[i].name);
    if (i != 2) CHECK(bag->topics()[i].first_record_ns == kJazzy[i].first);  // 2: /cam1/camera_info, cut
    CHECK(bag->topics()[i].last_record_ns == kJazzy[i].last);
  }
  CHECK(bag->findTopic("/cam1/camera_info")->message_count == cam1_info);
  CHECK(bag->findTopic("/cam1/camera_info")->first_record_ns >= kMid);
  CHECK(bag->findTopic("/joint_states")->message_count == 4121);
  const auto got = readAll(*bag);
  CHECK(got.size() == want.size());
  CHECK(got == want);
  // A topic only the second file has, asked alone: the first file is skipped, not read whole.
  const auto only = readAll(*bag, {"/cam1/camera_info"});
  CHECK(only.size() == cam1_info);
  CHECK((!only.empty() && only.front().index == 0 && only.back().index == cam1_info - 1));
  // The topics a reading delivers point into the folder's own topic list.
  bag->read({"/joint_states"}, [&](const RawMessage& m) {
    CHECK(m.topic == bag->findTopic("/joint_states"));
    return false;
  });

  // The same two files without metadata.yaml, named so that plain string
  // order would put the second first: natural order reads bag_9 before bag_10.
  fs::create_directories(tmp / "nometa");
  fs::copy_file(tmp / "split/split_0.db3", tmp / "nometa/bag_9.db3");
  fs::copy_file(tmp / "split/split_1.db3", tmp / "nometa/bag_10.db3");
  const auto nometa = openBag(tmp / "nometa");
  CHECK(nometa->format().find("no metadata.yaml") != std::string::npos);
  CHECK(readAll(*nometa) == want);
}

TEST_CASE("sqlite: metadata.yaml that names a missing file, or disagrees with the storage", "[logs][sqlite][folder]") {
  FGCAL_REQUIRE_SHARED_DATA(db3, anymal("anymal_small_humble_db3/anymal_small_humble_db3_0.db3"));
  TempDir tmp;
  copyFixture(db3, tmp / "bag/b_0.db3");
  const std::vector<std::pair<std::string, std::uint64_t>> right = {
      {"/cam0/camera_info", 3}, {"/cam0/image_raw", 3}, {"/cam1/camera_info", 3},
      {"/cam1/image_raw/compressed", 3}, {"/joint_states", 264}};

  SECTION("a listed file that is missing is an error: the bag would be read without it") {
    writeFile(tmp / "bag/metadata.yaml", metadataYaml(9, {"b_0.db3", "b_1.db3"}, 276, right));
    const std::string e = logError([&] { openBag(tmp / "bag"); });
    CHECK(e.find("metadata.yaml") != std::string::npos);
    CHECK(e.find("relative_file_paths[1]") != std::string::npos);
    CHECK(e.find("names b_1.db3, which is not a file") != std::string::npos);
  }
  SECTION("a file listed twice is an error: its messages would be read twice") {
    writeFile(tmp / "bag/metadata.yaml", metadataYaml(8, {"b_0.db3", "b_0.db3"}, 552, right));
    CHECK(logError([&] { openBag(tmp / "bag"); }).find("names b_0.db3 a second time (also entry 0)") !=
          std::string::npos);
  }
  SECTION("before version 4, the paths may start with the folder's name (relative to its parent)") {
    writeFile(tmp / "bag/metadata.yaml", metadataYaml(3, {"bag/b_0.db3"}, 276, right));
    const auto bag = openBag(tmp / "bag");
    CHECK(bag->format().find("metadata version 3") != std::string::npos);
    CHECK(bag->format().find("WARNING") == std::string::npos);
    CHECK(readAll(*bag).size() == 276);
    // From version 4 on they are relative to the folder itself.
    writeFile(tmp / "bag/metadata.yaml", metadataYaml(4, {"bag/b_0.db3"}, 276, right));
    CHECK(logError([&] { openBag(tmp / "bag"); }).find("names bag/b_0.db3, which is not a file") != std::string::npos);
  }
  SECTION("counts that disagree are a warning in format(); the storage's counts are used") {
    auto wrong = right;
    wrong.back().second = 300;
    writeFile(tmp / "bag/metadata.yaml", metadataYaml(4, {"b_0.db3"}, 312, wrong));
    const auto bag = openBag(tmp / "bag");
    const std::string f = bag->format();
    CHECK(f.find("WARNING") != std::string::npos);
    CHECK(f.find("metadata.yaml states 312 messages, the files hold 276") != std::string::npos);
    CHECK(f.find("topic /joint_states: metadata.yaml states 300 messages, the files hold 264") != std::string::npos);
    CHECK(bag->findTopic("/joint_states")->message_count == 264);
    CHECK(readAll(*bag).size() == 276);
  }
  SECTION("a type that disagrees is an error") {
    writeFile(tmp / "bag/metadata.yaml", metadataYaml(5, {"b_0.db3"}, 276, right, "sensor_msgs/msg/Imu"));
    const std::string e = logError([&] { openBag(tmp / "bag"); });
    CHECK(e.find("topic /joint_states") != std::string::npos);
    CHECK(e.find("sensor_msgs/msg/Imu") != std::string::npos);
  }
  SECTION("metadata.yaml without version, not YAML, or with whole-file compression") {
    writeFile(tmp / "bag/metadata.yaml", "rosbag2_bagfile_information:\n  relative_file_paths: [b_0.db3]\n");
    CHECK(logError([&] { openBag(tmp / "bag"); }).find("rosbag2_bagfile_information.version: missing") !=
          std::string::npos);
    writeFile(tmp / "bag/metadata.yaml", "rosbag2_bagfile_information: [\n");
    CHECK(logError([&] { openBag(tmp / "bag"); }).find("not valid YAML") != std::string::npos);
    std::string y = metadataYaml(9, {"b_0.db3"}, 276, right);
    y.replace(y.find("compression_format: \"\""), 22, "compression_format: zstd");
    y.replace(y.find("compression_mode: \"\""), 20, "compression_mode: FILE");
    writeFile(tmp / "bag/metadata.yaml", y);
    CHECK(logError([&] { openBag(tmp / "bag"); }).find("compression_mode: is FILE") != std::string::npos);
  }
}

// --- damaged or hostile db3 files ---------------------------------------------

TEST_CASE("sqlite: each damaged db3 gives its LogError", "[logs][sqlite][errors]") {
  FGCAL_REQUIRE_SHARED_DATA(src, anymal("anymal_small_humble_db3/anymal_small_humble_db3_0.db3"));
  TempDir tmp;
  const std::string db3 = tmp / "bag.db3";
  copyFixture(src, db3);

  SECTION("not an SQLite file behind an SQLite header") {
    writeFile(db3, std::string("SQLite format 3\0", 16) + std::string(4080, 'x'));
    const std::string e = logError([&] { openBag(db3); });
    CHECK(e.find(db3) == 0);
    CHECK(e.find("not an SQLite database: expected a rosbag2 sqlite3 (.db3) file") != std::string::npos);
  }
  SECTION("a folder whose db3 is not an SQLite file") {
    writeFile(tmp / "folder/x_0.db3", "plain text, not a database at all");
    const std::string e = logError([&] { openBag(tmp / "folder"); });
    CHECK(e.find(tmp / "folder/x_0.db3") == 0);
    CHECK(e.find("not an SQLite database") != std::string::npos);
  }
  SECTION("no messages table") {
    execSql(db3, "DROP TABLE messages;");
    CHECK(logError([&] { openBag(db3); }) ==
          db3 + ": table messages: not found: a rosbag2 sqlite3 file has the tables topics and messages (found: "
                "metadata, schema, topics)");
  }
  SECTION("no topics table") {
    execSql(db3, "DROP TABLE topics;");
    CHECK(logError([&] { openBag(db3); }).find("table topics: not found") != std::string::npos);
  }
  SECTION("a messages table without the data column") {
    execSql(db3, "ALTER TABLE messages DROP COLUMN data;");
    CHECK(logError([&] { openBag(db3); }).find("table messages: has no column data") != std::string::npos);
  }
  SECTION("a topic_id in messages without a topic") {
    execSql(db3, "UPDATE messages SET topic_id = 99 WHERE id IN (7, 8);");
    CHECK(logError([&] { openBag(db3); }) ==
          db3 + ": table messages, id 7: 2 message(s) have topic_id '99', which is no topic of table topics (its ids: "
                "1, 2, 3, 4, 5)");
  }
  SECTION("NULL data") {
    // rosbag2 declares data NOT NULL; a hand-edited table may not.
    execSql(db3,
            "CREATE TABLE m2(id INTEGER PRIMARY KEY, topic_id INTEGER, timestamp INTEGER, data BLOB);"
            "INSERT INTO m2 SELECT * FROM messages; DROP TABLE messages; ALTER TABLE m2 RENAME TO messages;"
            "UPDATE messages SET data = NULL WHERE id = (SELECT id FROM messages WHERE topic_id = 2 "
            "ORDER BY timestamp, id LIMIT 1 OFFSET 1);");
    const auto bag = openBag(db3);
    CHECK(readAll(*bag, {"/joint_states"}).size() == 264);  // other topics still read
    const std::string e = logError([&] { readAll(*bag, {"/cam0/image_raw"}); });
    CHECK(e.find(db3 + ": topic /cam0/image_raw, message 1 (record time ") == 0);
    CHECK(e.find("data is NULL, expected a blob of serialized sensor_msgs/msg/Image") != std::string::npos);
  }
  SECTION("text instead of a blob") {
    execSql(db3, "UPDATE messages SET data = 'abc' WHERE id = (SELECT MIN(id) FROM messages WHERE topic_id = 1);");
    const auto bag = openBag(db3);
    const std::string e = logError([&] { readAll(*bag); });
    CHECK(e.find("topic /joint_states, message 0") != std::string::npos);
    CHECK(e.find("data is text, expected a blob") != std::string::npos);
  }
  SECTION("a blob larger than ReadLimits::max_chunk_bytes") {
    ReadLimits small;
    small.max_chunk_bytes = 100000;  // joint states and camera infos fit, a 640x480 image does not
    const auto bag = openBag(db3, small);
    CHECK(readAll(*bag, {"/joint_states", "/cam0/camera_info"}).size() == 267);
    const std::string e = logError([&] { readAll(*bag, {"/cam0/image_raw"}); });
    CHECK(e.find("topic /cam0/image_raw, message 0") != std::string::npos);
    CHECK(e.find("more than the limit of 100000 bytes (ReadLimits::max_chunk_bytes)") != std::string::npos);
  }
  SECTION("a topic asked for that the bag does not have") {
    const auto bag = openBag(db3);
    CHECK(logError([&] { readAll(*bag, {"/joint_states", "/imu"}); }) ==
          db3 + ": topic /imu: not in the bag; its topics are: /cam0/camera_info, /cam0/image_raw, "
                "/cam1/camera_info, /cam1/image_raw/compressed, /joint_states");
  }
  SECTION("an unknown serialization_format is listed, but reading that topic is an error") {
    execSql(db3, "UPDATE topics SET serialization_format = 'json' WHERE name = '/cam1/camera_info';");
    const auto bag = openBag(db3);
    REQUIRE(bag->findTopic("/cam1/camera_info"));
    CHECK(bag->findTopic("/cam1/camera_info")->message_count == 3);
    CHECK(readAll(*bag, {"/joint_states"}).size() == 264);
    const std::string e = logError([&] { readAll(*bag, {"/cam1/camera_info"}); });
    CHECK(e == db3 + ": topic /cam1/camera_info: serialization_format 'json' cannot be read; expected 'cdr' (ask for "
                     "the other topics by name)");
    CHECK(logError([&] { readAll(*bag); }) == e);
  }
  SECTION("a timestamp that is not an integer") {
    execSql(db3, "UPDATE messages SET timestamp = 'soon' WHERE id = 5;");
    CHECK(logError([&] { openBag(db3); }) ==
          db3 + ": topic /joint_states: 1 message(s) have a timestamp that is not an integer; expected nanoseconds");
  }
  SECTION("a topic listed twice") {
    execSql(db3, "INSERT INTO topics VALUES (9, '/joint_states', 'sensor_msgs/msg/JointState', 'cdr', '');");
    CHECK(logError([&] { openBag(db3); }).find("topic /joint_states is listed twice") != std::string::npos);
  }
  SECTION("a timestamp index that lacks rows of the table") {
    // The index is built partial (without the joint states), then declared
    // whole: sqlite walks it for the timestamp order and misses those rows.
    execSql(db3,
            "DROP INDEX timestamp_idx;"
            "CREATE INDEX timestamp_idx ON messages (timestamp ASC) WHERE topic_id <> 1;"
            "PRAGMA writable_schema = ON;"
            "UPDATE sqlite_master SET sql = 'CREATE INDEX timestamp_idx ON messages (timestamp ASC)' "
            "WHERE name = 'timestamp_idx';");
    const auto bag = openBag(db3);
    CHECK(bag->findTopic("/joint_states")->message_count == 264);  // counted from the table
    CHECK(logError([&] { readAll(*bag, {"/joint_states"}); }) ==
          db3 + ": topic /joint_states: the file is damaged: 264 messages counted, but reading in timestamp order "
                "found 0");
  }
  SECTION("a file cut short") {
    fs::resize_file(db3, fs::file_size(db3) / 2);
    const std::string e = logError([&] {
      const auto bag = openBag(db3);
      readAll(*bag);
    });
    CHECK(e.find(db3) == 0);
    CHECK(e.find("damaged") != std::string::npos);
  }
}

TEST_CASE("sqlite: the fixture folder itself is read-only and opens without -wal/-shm files", "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, anymal("anymal_small_humble_db3"));
  const auto bag = openBag(dir);
  CHECK(readAll(*bag).size() == 276);
  std::error_code ec;
  CHECK_FALSE(fs::exists(dir + "/anymal_small_humble_db3_0.db3-shm", ec));
  CHECK_FALSE(fs::exists(dir + "/anymal_small_humble_db3_0.db3-wal", ec));
}

TEST_CASE("sqlite: a path with spaces, '%', '?' and '#' (sqlite opens it as a URI)", "[logs][sqlite]") {
  FGCAL_REQUIRE_SHARED_DATA(src, anymal("anymal_small_humble_db3/anymal_small_humble_db3_0.db3"));
  TempDir tmp;
  const std::string dir = tmp / "run 1 %41 ?x=1 #2";
  copyFixture(src, dir + "/b_0.db3");
  CHECK(readAll(*openBag(dir + "/b_0.db3")).size() == 276);
  CHECK(readAll(*openBag(dir)).size() == 276);
}

TEST_CASE("sqlite: a db3 with a -wal file beside it is read with the messages the -wal holds", "[logs][sqlite]") {
  // A recorder that did not close its bag leaves messages in the -wal file;
  // opening such a file "immutable" would silently miss them.
  FGCAL_REQUIRE_SHARED_DATA(src, anymal("anymal_small_humble_db3/anymal_small_humble_db3_0.db3"));
  TempDir tmp;
  const std::string db3 = tmp / "bag.db3";
  copyFixture(src, db3);
  sqlite3* writer = nullptr;
  REQUIRE(sqlite3_open_v2(db3.c_str(), &writer, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK);
  REQUIRE(sqlite3_exec(writer,
                       "PRAGMA journal_mode = WAL; PRAGMA wal_autocheckpoint = 0;"
                       "DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '/joint_states');",
                       nullptr, nullptr, nullptr) == SQLITE_OK);
  REQUIRE(fs::file_size(db3 + "-wal") > 0);
  {
    const auto bag = openBag(db3);
    CHECK(bag->findTopic("/joint_states")->message_count == 0);
    CHECK(readAll(*bag).size() == 12);
  }
  sqlite3_close(writer);
}

namespace {
/// Every file of a folder: name -> bytes.
std::map<std::string, std::string> folderSnapshot(const std::string& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out[e.path().filename().string()] = fgcal::test::readFile(e.path());
  return out;
}

std::size_t privateCopies() {
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path()))
    n += e.path().filename().string().rfind("fgcal-db3-", 0) == 0 ? 1 : 0;
  return n;
}
}  // namespace

TEST_CASE("sqlite: opening a bag left with a -wal file never writes into its folder, and reads the -wal's messages",
          "[logs][sqlite][folder]") {
  FGCAL_REQUIRE_SHARED_DATA(src, anymal("anymal_small_humble_db3"));
  TempDir tmp;
  const std::string dir = tmp / "bag";
  const std::string db3 = dir + "/anymal_small_humble_db3_0.db3";
  copyFixture(src + "/anymal_small_humble_db3_0.db3", db3);
  copyFixture(src + "/metadata.yaml", dir + "/metadata.yaml");
  {
    // A recorder that stopped without a checkpoint: its last changes are only
    // in the -wal (here the joint samples deleted and one CameraInfo added).
    sqlite3* writer = nullptr;
    REQUIRE(sqlite3_open_v2(db3.c_str(), &writer, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK);
    int off = 0;
    REQUIRE(sqlite3_db_config(writer, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, &off) == SQLITE_OK);
    REQUIRE(sqlite3_exec(writer,
                         "PRAGMA journal_mode = WAL; PRAGMA wal_autocheckpoint = 0;"
                         "DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '/joint_states');"
                         "INSERT INTO messages (topic_id, timestamp, data) SELECT topic_id, timestamp + 1, data "
                         "FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '/cam0/camera_info') "
                         "ORDER BY timestamp DESC LIMIT 1;",
                         nullptr, nullptr, nullptr) == SQLITE_OK);
    sqlite3_close(writer);
  }
  std::error_code ec;
  fs::remove(db3 + "-shm", ec);  // the recorder's wal-index goes with its process
  REQUIRE(fs::file_size(db3 + "-wal") > 0);
  const auto before = folderSnapshot(dir);
  REQUIRE(before.size() == 3);  // the .db3, its -wal and metadata.yaml
  const std::size_t copies = privateCopies();
  {
    const auto bag = openBag(db3);
    CHECK(folderSnapshot(dir) == before);  // no -shm beside it while it is open
    CHECK(bag->findTopic("/joint_states")->message_count == 0);
    CHECK(bag->findTopic("/cam0/camera_info")->message_count == 4);
    CHECK(readAll(*bag).size() == 13);
  }
  CHECK(folderSnapshot(dir) == before);
  CHECK(privateCopies() == copies);  // the private copy is gone with the reader
  // Without a -wal, the file is opened in place, immutable, and nothing is written either.
  fs::remove(db3 + "-wal");
  const auto plain = folderSnapshot(dir);
  CHECK(readAll(*openBag(db3)).size() == 276);
  CHECK(folderSnapshot(dir) == plain);
}

TEST_CASE("sqlite: a bag whose messages are zstd-compressed one by one (compression_mode MESSAGE)",
          "[logs][sqlite][folder]") {
  FGCAL_REQUIRE_SHARED_DATA(src, anymal("anymal_small_humble_db3"));
  TempDir tmp;
  const std::string db3 = tmp / "bag/bag_0.db3";
  copyFixture(src + "/anymal_small_humble_db3_0.db3", db3);
  const auto plain = readAll(*openBag(db3));
  {
    // Compress every blob in place, as rosbag2's sequential compression writer does.
    sqlite3* db = nullptr;
    REQUIRE(sqlite3_open_v2(db3.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK);
    sqlite3_stmt* sel = nullptr;
    sqlite3_stmt* upd = nullptr;
    REQUIRE(sqlite3_prepare_v2(db, "SELECT id, data FROM messages", -1, &sel, nullptr) == SQLITE_OK);
    REQUIRE(sqlite3_prepare_v2(db, "UPDATE messages SET data = ?2 WHERE id = ?1", -1, &upd, nullptr) == SQLITE_OK);
    std::vector<std::pair<sqlite3_int64, std::vector<char>>> rows;
    while (sqlite3_step(sel) == SQLITE_ROW) {
      const auto* p = static_cast<const char*>(sqlite3_column_blob(sel, 1));
      const std::size_t n = static_cast<std::size_t>(sqlite3_column_bytes(sel, 1));
      std::vector<char> z(ZSTD_compressBound(n));
      z.resize(ZSTD_compress(z.data(), z.size(), p, n, 1));
      rows.emplace_back(sqlite3_column_int64(sel, 0), std::move(z));
    }
    sqlite3_finalize(sel);
    sqlite3_exec(db, "BEGIN", nullptr, nullptr, nullptr);
    for (const auto& [id, z] : rows) {
      sqlite3_reset(upd);
      sqlite3_bind_int64(upd, 1, id);
      sqlite3_bind_blob(upd, 2, z.data(), static_cast<int>(z.size()), SQLITE_STATIC);
      REQUIRE(sqlite3_step(upd) == SQLITE_DONE);
    }
    sqlite3_exec(db, "COMMIT", nullptr, nullptr, nullptr);
    sqlite3_finalize(upd);
    sqlite3_close(db);
  }
  std::string y = metadataYaml(9, {"bag_0.db3"}, 276,
                               {{"/cam0/camera_info", 3}, {"/cam0/image_raw", 3}, {"/cam1/camera_info", 3},
                                {"/cam1/image_raw/compressed", 3}, {"/joint_states", 264}});
  y.replace(y.find("compression_format: \"\""), 22, "compression_format: zstd");
  y.replace(y.find("compression_mode: \"\""), 20, "compression_mode: MESSAGE");
  writeFile(tmp / "bag/metadata.yaml", y);
  const auto bag = openBag(tmp / "bag");
  CHECK(bag->format().find("messages compressed with zstd") != std::string::npos);
  CHECK(readAll(*bag) == plain);

  // A blob that is not a zstd frame.
  execSql(db3, "UPDATE messages SET data = x'00010000' WHERE id = (SELECT MIN(id) FROM messages WHERE topic_id = 3);");
  const std::string e = logError([&] { readAll(*openBag(tmp / "bag"), {"/cam0/camera_info"}); });
  CHECK(e.find("topic /cam0/camera_info, message 0") != std::string::npos);
  CHECK(e.find("expected a zstd frame") != std::string::npos);
}
