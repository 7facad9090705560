// fgcal bag-info: topics, counts, record-time span, rates and header stamps of
// the shared bags; rosbag2's own test bags are checked against the
// metadata.yaml rosbag2 wrote beside them, the ANYmal bag against its README.
// The command itself: output on stdout, exit 2 with the reader's message on a
// bad bag.

#include <cstdlib>
#include <map>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "apps_test_util.hpp"
#include "cli_test_util.hpp"
#include "fgcal/apps/bag_info.hpp"
#include "fgcal_test/shared_data.hpp"

using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {

const BagTopicSummary* findTopic(const BagSummary& s, const std::string& name) {
  for (const auto& t : s.topics)
    if (t.name == name) return &t;
  return nullptr;
}

CliRun runBagInfo(const std::string& args) {
  TempDir tmp;
  return runCommand(FGCAL_EXE, "bag-info " + args, tmp.path());
}

}  // namespace

TEST_CASE("bag-info: rosbag2's own bags give the topics and counts of their metadata.yaml", "[apps][bag_info]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/rosbag2_tests/resources");
  for (const char* bag : {"sqlite3/cdr_test", "mcap/cdr_test", "sqlite3/bag_with_topics_and_service_events",
                          "mcap/bag_with_topics_and_service_events"}) {
    SECTION(bag) {
      const std::string folder = dir + "/" + bag;
      const YAML::Node info = YAML::LoadFile(folder + "/metadata.yaml")["rosbag2_bagfile_information"];
      REQUIRE(info.IsMap());
      const BagSummary s = summarizeBag(folder);
      CHECK(s.message_count == info["message_count"].as<std::uint64_t>());
      const YAML::Node topics = info["topics_with_message_count"];
      REQUIRE(s.topics.size() == topics.size());
      const std::string text = formatBagInfo(s);
      INFO(text);
      for (const auto& entry : topics) {
        const std::string name = entry["topic_metadata"]["name"].as<std::string>();
        const BagTopicSummary* t = findTopic(s, name);
        REQUIRE(t != nullptr);
        CHECK(t->type == entry["topic_metadata"]["type"].as<std::string>());
        CHECK(t->serialization == entry["topic_metadata"]["serialization_format"].as<std::string>());
        CHECK(t->message_count == entry["message_count"].as<std::uint64_t>());
        // the printed row: name, type and count in that order
        const auto row = text.find("  " + name + " ");
        REQUIRE(row != std::string::npos);
        const std::string line = text.substr(row, text.find('\n', row) - row);
        CHECK_THAT(line, Catch::Contains(" " + t->type + " ") &&
                             Catch::Contains(" " + std::to_string(t->message_count) + " "));
      }
      // The record-time span rosbag2 wrote: starting_time and duration.
      const auto start = info["starting_time"]["nanoseconds_since_epoch"].as<std::int64_t>();
      const auto length = info["duration"]["nanoseconds"].as<std::int64_t>();
      CHECK(s.start_ns == start);
      CHECK(s.end_ns - s.start_ns == length);
      CHECK_THAT(text, Catch::Contains("messages: " + std::to_string(s.message_count)) &&
                           Catch::Contains("format:   " + s.format));
      CHECK_THAT(s.format, Catch::Contains("metadata version"));  // read as a rosbag2 folder
      CHECK(s.size_bytes > 0);
      // Service events and test_msgs are not types of ours: no stamps read, no error.
      const BagSummary with_stamps = summarizeBag(folder, true);
      for (const auto& t : with_stamps.topics) CHECK_FALSE(t.stamps_read);
    }
  }
}

TEST_CASE("bag-info: the ANYmal bag in its three formats", "[apps][bag_info]") {
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const std::map<std::string, std::uint64_t> counts{{"/joint_states", 4121},
                                                   {"/cam0/image_raw", 40},
                                                   {"/cam0/camera_info", 40},
                                                   {"/cam1/image_raw/compressed", 40},
                                                   {"/cam1/camera_info", 40}};
  const std::int64_t first_joint = 1700877873968399947, last_joint = 1700877894568399947;
  const std::int64_t first_image = 1700877874268399947, last_image = 1700877894267864430;
  for (const char* bag : {"anymal_small.bag", "anymal_small.mcap", "anymal_small_db3"}) {
    SECTION(bag) {
      const BagSummary s = summarizeBag(dir + "/" + bag, true);
      REQUIRE(s.topics.size() == 5);
      for (const auto& [name, n] : counts) {
        const BagTopicSummary* t = findTopic(s, name);
        REQUIRE(t != nullptr);
        CHECK(t->message_count == n);
        CHECK(t->known_type);
        CHECK(t->stamps_read);
      }
      CHECK(s.message_count == 4281);
      // README: record time = header stamp + 1..8 ms latency.
      CHECK(s.start_ns - first_joint >= 1000000);
      CHECK(s.start_ns - first_joint <= 8000000);
      const BagTopicSummary& js = *findTopic(s, "/joint_states");
      CHECK(js.min_stamp_ns == first_joint);
      CHECK(js.max_stamp_ns == last_joint);
      CHECK(js.rate_hz == Approx(200.0).epsilon(0.01));
      CHECK(js.stamps_out_of_order > 0);  // stored in record order, not stamp order
      const BagTopicSummary& img = *findTopic(s, "/cam1/image_raw/compressed");
      CHECK(img.min_stamp_ns == first_image);
      CHECK(img.max_stamp_ns == last_image);
      CHECK(img.rate_hz == Approx(39.0 / 20.0).epsilon(0.01));
      CHECK(img.serialization == (std::string(bag) == "anymal_small.bag" ? "ros1" : "cdr"));

      const std::string text = formatBagInfo(s);
      INFO(text);
      CHECK_THAT(text, Catch::Contains("2023-11-25 02:04:33.9") && Catch::Contains("UTC") &&
                           Catch::Contains("duration: 20.5") && Catch::Contains("messages: 4281") &&
                           Catch::Contains("1700877873.968399947 .. 1700877894.568399947") &&
                           Catch::Contains("200.0 Hz"));
    }
  }
  SECTION("without --stamps nothing but the index is read") {
    const BagSummary s = summarizeBag(dir + "/anymal_small.bag");
    for (const auto& t : s.topics) CHECK_FALSE(t.stamps_read);
    CHECK_THAT(formatBagInfo(s), !Catch::Contains("header stamps"));
  }
}

TEST_CASE("bag-info: UTC dates", "[apps][bag_info]") {
  CHECK(formatUtc(0) == "1970-01-01 00:00:00.000000000 UTC");
  CHECK(formatUtc(1700877873968399947) == "2023-11-25 02:04:33.968399947 UTC");
  CHECK(formatUtc(-1) == "1969-12-31 23:59:59.999999999 UTC");
}

TEST_CASE("bag-info: a bad bag is an InputError with the reader's message", "[apps][bag_info]") {
  TempDir tmp;
  CHECK_INPUT_ERROR(summarizeBag(tmp / "missing.bag"), "missing.bag", "", "not found");
  writeFile(tmp / "notes.bag", "these are not the bytes of a bag\n");
  CHECK_INPUT_ERROR(summarizeBag(tmp / "notes.bag"), "notes.bag", "offset 0", "#ROSBAG V2.0");
  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  // cut short in the middle of its first chunk
  const std::string whole = readFile(dir + "/anymal_small.bag");
  writeFile(tmp / "cut.bag", whole.substr(0, 100000));
  CHECK_INPUT_ERROR(summarizeBag(tmp / "cut.bag"), "cut.bag", "offset", "cut short");
}

TEST_CASE("bag-info: the command prints the summary and exits 2 on a bad bag", "[apps][bag_info]") {
  TempDir tmp;
  writeFile(tmp / "notes.mcap", "not an mcap");
  const CliRun bad = runBagInfo(quoted(tmp / "notes.mcap"));
  CHECK(bad.exit_code == 2);
  CHECK_THAT(bad.err, Catch::Contains("notes.mcap") && Catch::Contains("MCAP"));
  CHECK(bad.out.empty());
  CHECK(runBagInfo("").exit_code == 2);  // the bag argument is required

  FGCAL_REQUIRE_SHARED_DATA(dir, "bags/anymal_small");
  const CliRun ok = runBagInfo("--stamps " + quoted(dir + "/anymal_small.mcap"));
  CHECK(ok.exit_code == 0);
  CHECK_THAT(ok.out, Catch::Contains("format:   MCAP") && Catch::Contains("/joint_states") &&
                         Catch::Contains("4121") && Catch::Contains("header stamps"));
}
