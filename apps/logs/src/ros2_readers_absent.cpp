// Compiled only while this branch lacks the ROS 2 readers (apps/logs/
// CMakeLists.txt adds it when one of their files is absent, with one
// FGCAL_LOGS_WITHOUT_* definition per absent file): openBag and the decoders
// then refuse ROS 2 input with a LogError saying so, instead of the library
// failing to link. Once the ROS 2 files are in, this file compiles to nothing
// and can be deleted.
#include "fgcal/logs/log_error.hpp"
#include "message_decoders.hpp"
#include "readers.hpp"

namespace fgcal::logs::detail {

namespace {
[[noreturn]] void absent(const std::string& file, const std::string& where, const char* what) {
  throw LogError(file, where, std::string(what) + " is not built into this version of fgcal");
}
}  // namespace

#ifdef FGCAL_LOGS_WITHOUT_MCAP
std::unique_ptr<BagReader> openMcapFile(const std::string& path, const ReadLimits&) {
  absent(path, "", "the MCAP reader");
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
#ifdef FGCAL_LOGS_WITHOUT_CDR
JointState decodeCdrJointState(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the CDR decoder");
}
Image decodeCdrImage(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the CDR decoder");
}
CompressedImage decodeCdrCompressedImage(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the CDR decoder");
}
CameraInfo decodeCdrCameraInfo(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the CDR decoder");
}
std::int64_t decodeCdrHeaderStamp(const RawMessage&, const std::string& file, const std::string& where) {
  absent(file, where, "the CDR decoder");
}
#endif

}  // namespace fgcal::logs::detail
