// Fuzz target: the rig.yaml reader (parseRigConfig) on arbitrary text. A rig
// that is accepted must also survive writeRigConfig and read back equal in its
// camera count and names (the writer quotes what the reader accepts), and in
// the joint offsets' prior.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/rig_config.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::apps;
  if (size > 64 * 1024) return 0;  // rig.yaml files are a few KB; bound the work per input
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const RigConfig rig = parseRigConfig(text, "rig.yaml", "/fuzz");
    const RigConfig back = parseRigConfig(writeRigConfig(rig), "rig.yaml (written back)", "/fuzz");
    if (back.cameras.size() != rig.cameras.size()) {
      std::fprintf(stderr, "round trip changed the camera count\n");
      std::abort();
    }
    if (back.robot.joint_offset_sigma != rig.robot.joint_offset_sigma ||
        back.robot.joint_offset_sigmas != rig.robot.joint_offset_sigmas) {
      std::fprintf(stderr, "round trip changed robot.joint_offset_sigma\n");
      std::abort();
    }
    for (std::size_t i = 0; i < rig.cameras.size(); ++i)
      if (back.cameras[i].name != rig.cameras[i].name) {
        std::fprintf(stderr, "round trip changed camera name '%s'\n", rig.cameras[i].name.c_str());
        std::abort();
      }
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
