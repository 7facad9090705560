// Fuzz target: the joints.csv reader (parseJointsCsv) on arbitrary text; an
// accepted log is interpolated at and around its stamps and written back.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fgcal::apps;
  if (size > 256 * 1024) return 0;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const JointLog log = parseJointsCsv(text, "joints.csv");
    std::vector<int> columns;
    for (std::size_t i = 0; i < log.names.size(); ++i) columns.push_back(static_cast<int>(i));
    columns.push_back(-1);  // an absent column must be refused, not read
    const auto& st = log.stamps_ns;
    for (std::size_t i = 0; i < st.size() && i < 64; ++i) {
      std::string why;
      if (interpolate(log, st[i], columns, &why)) {
        std::fprintf(stderr, "interpolate read an absent joint column (-1)\n");
        std::abort();
      }
      columns.pop_back();
      (void)interpolate(log, st[i], columns, &why);
      if (i + 1 < st.size()) {
        const uint64_t half = (static_cast<uint64_t>(st[i + 1]) - static_cast<uint64_t>(st[i])) / 2;
        (void)interpolate(log, static_cast<int64_t>(static_cast<uint64_t>(st[i]) + half), columns, &why);
      }
      columns.push_back(-1);
    }
    if (!st.empty()) {
      std::string why;
      if (st.front() > std::numeric_limits<int64_t>::min()) (void)interpolate(log, st.front() - 1, {}, &why);
      if (st.back() < std::numeric_limits<int64_t>::max()) (void)interpolate(log, st.back() + 1, {}, &why);
    }
    const JointLog back = parseJointsCsv(formatJointsCsv(log.names, log.stamps_ns, log.positions), "written back");
    if (back.stamps_ns != log.stamps_ns || back.names != log.names) {
      std::fprintf(stderr, "round trip changed the stamps or names\n");
      std::abort();
    }
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    fgcal::fuzz::unexpected(e);
  }
  return 0;
}
