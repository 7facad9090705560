// Makes the seed corpus of fuzz_sqlite_bag at fuzz-build time from the shared
// fixtures (never committed: shared data stays out of the repository):
//   fuzz_sqlite_bag_seeds SHARED_BAGS_DIR OUT_DIR
// Each seed is a copy of a real rosbag2 file cut down with SQL (a few joint
// states, one CameraInfo per camera, one JPEG) and rewritten with 512-byte
// pages, so it stays under the fuzzer's 64 KiB input cap.
#include <sqlite3.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;

namespace {

bool run(const std::string& db3, const std::string& sql) {
  sqlite3* db = nullptr;
  bool ok = sqlite3_open_v2(db3.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) == SQLITE_OK;
  char* err = nullptr;
  if (ok && sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::fprintf(stderr, "fuzz_sqlite_bag_seeds: %s: %s\n", db3.c_str(), err ? err : "?");
    ok = false;
  }
  sqlite3_free(err);
  sqlite3_close(db);
  return ok;
}

bool seed(const fs::path& from, const fs::path& to, const std::string& cut) {
  std::error_code ec;
  fs::copy_file(from, to, fs::copy_options::overwrite_existing, ec);
  if (ec) {
    std::fprintf(stderr, "fuzz_sqlite_bag_seeds: cannot copy %s: %s\n", from.c_str(), ec.message().c_str());
    return false;
  }
  fs::permissions(to, fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace, ec);
  if (!run(to.string(), cut + "PRAGMA page_size = 512; VACUUM;")) return false;
  const auto size = fs::file_size(to, ec);
  std::printf("  seed %s: %ju bytes\n", to.filename().c_str(), static_cast<std::uintmax_t>(size));
  if (size > 64 * 1024) {
    std::fprintf(stderr, "fuzz_sqlite_bag_seeds: %s is larger than the target's 64 KiB cap\n", to.c_str());
    return false;
  }
  return true;
}

/// Keeps the first `n` messages (timestamp order) of the topic named `topic`.
std::string keepFirst(const std::string& topic, int n) {
  return "DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '" + topic +
         "') AND id NOT IN (SELECT id FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '" + topic +
         "') ORDER BY timestamp, id LIMIT " + std::to_string(n) + ");";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: fuzz_sqlite_bag_seeds SHARED_BAGS_DIR OUT_DIR\n");
    return 2;
  }
  const fs::path bags(argv[1]), out(argv[2]);
  std::error_code ec;
  fs::create_directories(out, ec);
  const fs::path humble = bags / "anymal_small/anymal_small_humble_db3/anymal_small_humble_db3_0.db3";
  const fs::path jazzy = bags / "anymal_small/anymal_small_db3/anymal_small_db3_0.db3";
  const fs::path tests = bags / "rosbag2_tests/resources/sqlite3";
  bool ok = true;
  // Humble layout: joint states and camera infos, image topics listed but empty.
  ok &= seed(humble, out / "humble_joints_infos.db3",
             keepFirst("/joint_states", 12) + keepFirst("/cam0/camera_info", 1) + keepFirst("/cam1/camera_info", 1) +
                 "DELETE FROM messages WHERE topic_id IN (SELECT id FROM topics WHERE name LIKE '%image%');");
  // Jazzy layout (message_definitions): one JPEG and its CameraInfo; the metadata rows
  // and one definition go to fit the cap.
  ok &= seed(jazzy, out / "jazzy_one_jpeg.db3",
             keepFirst("/cam1/image_raw/compressed", 1) + keepFirst("/cam1/camera_info", 1) +
                 "DELETE FROM messages WHERE topic_id IN (SELECT id FROM topics WHERE name NOT LIKE '/cam1/%');"
                 "DELETE FROM metadata; DELETE FROM message_definitions WHERE topic_type LIKE '%JointState';");
  // Written by rosbag2 itself: test_msgs, service events, an empty topic.
  ok &= seed(tests / "cdr_test/cdr_test_0.db3", out / "rosbag2_cdr_test.db3", "");
  ok &= seed(tests / "bag_with_topics_and_service_events/bag_with_topics_and_service_events.db3",
             out / "rosbag2_service_events.db3", "");
  return ok ? 0 : 1;
}
