// Fuzz target: the CDR decoders. The same bytes go to each of the four
// sensor_msgs decoders and to decodeHeaderStamp, each time as a message of a
// fake topic of that type (serialization Cdr). A LogError is an answer;
// anything else (a crash, a read past the bytes, a huge allocation, another
// exception) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fgcal/logs/bag.hpp"
#include "fgcal/logs/log_error.hpp"
#include "fgcal/logs/messages.hpp"
#include "fuzz_common.hpp"

namespace {

template <class F>
void attempt(const F& f) {
  try {
    f();
  } catch (const fgcal::logs::LogError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::logs;
  if (size > 64 * 1024) return 0;
  static const TopicInfo topics[] = {
      {"/joint_states", "sensor_msgs/msg/JointState", Serialization::Cdr, "", 1, 0, 0},
      {"/image", "sensor_msgs/msg/Image", Serialization::Cdr, "", 1, 0, 0},
      {"/compressed", "sensor_msgs/msg/CompressedImage", Serialization::Cdr, "", 1, 0, 0},
      {"/camera_info", "sensor_msgs/msg/CameraInfo", Serialization::Cdr, "", 1, 0, 0},
  };
  const std::string file = "fuzz.cdr";
  RawMessage m;
  m.data = data;
  m.size = size;
  m.topic = &topics[0];
  attempt([&] { (void)decodeJointState(m, file); });
  attempt([&] { (void)decodeHeaderStamp(m, file); });
  m.topic = &topics[1];
  attempt([&] { (void)decodeImage(m, file); });
  m.topic = &topics[2];
  attempt([&] { (void)decodeCompressedImage(m, file); });
  m.topic = &topics[3];
  attempt([&] { (void)decodeCameraInfo(m, file); });
  return 0;
}
