// Compiled only while this branch lacks the ROS 1 and rosbag2 sqlite3/folder
// readers (apps/logs/CMakeLists.txt adds it when one of their files is
// absent, with one FGCAL_LOGS_WITHOUT_* definition per absent file): openBag
// and the decoders then refuse that input with a LogError saying so, instead
// of the library failing to link. Once those files are in, this file compiles
// to nothing and can be deleted.
#include "fgcal/logs/log_error.hpp"
#include "message_decoders.hpp"
#include "readers.hpp"

namespace fgcal::logs::detail {

namespace {
[[maybe_unused]] [[noreturn]] void absent(const std::string& file, const std::string& where, const char* what) {
  throw LogError(file, where, std::string(what) + " is not built into this version of fgcal");
}
}  // namespace

#ifdef FGCAL_LOGS_WITHOUT_ROS1
std::unique_ptr<BagReader> openRos1Bag(const std::string& path, const ReadLimits&) {
  absent(path, "", "the ROS 1 bag reader");
}
#endif
#ifdef FGCAL_LOGS_WITHOUT_ROS1_MESSAGES
JointState decodeRos1JointState(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the ROS 1 message decoder");
}
Image decodeRos1Image(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the ROS 1 message decoder");
}
CompressedImage decodeRos1CompressedImage(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the ROS 1 message decoder");
}
CameraInfo decodeRos1CameraInfo(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the ROS 1 message decoder");
}
std::int64_t decodeRos1HeaderStamp(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the ROS 1 message decoder");
}
#endif
#ifdef FGCAL_LOGS_WITHOUT_SQLITE
std::unique_ptr<BagReader> openSqliteFile(const std::string& path, const ReadLimits&) {
  absent(path, "", "the rosbag2 sqlite3 reader");
}
#endif
#ifdef FGCAL_LOGS_WITHOUT_ROSBAG2_FOLDER
std::unique_ptr<BagReader> openRosbag2Folder(const std::string& path, const ReadLimits&) {
  absent(path, "", "the rosbag2 folder reader");
}
#endif

}  // namespace fgcal::logs::detail
