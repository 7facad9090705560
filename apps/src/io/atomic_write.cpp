// Whole-file reads and atomic writes (see results_io.hpp): every output of
// fgcal goes through writeFileAtomically, so a crash, a full disk or a
// killed process never leaves a partly written calibration behind.
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fgcal/apps/errors.hpp"
#include "fgcal/apps/results_io.hpp"

namespace fs = std::filesystem;

namespace fgcal::apps {

std::string readTextFile(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "", what + " not found");
  if (fs::is_directory(path, ec)) throw InputError(path, "", "expected " + what + ", got a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open " + what + " for reading: " + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "error while reading " + what);
  return ss.str();
}

namespace {

std::string errnoText(int err) { return std::strerror(err); }

// Writes all of `data` to fd, retrying short writes and EINTR.
bool writeAll(int fd, const char* data, std::size_t size, int* err) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      *err = errno;
      return false;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& content, Durability durable) {
  const fs::path target(path);
  fs::path folder = target.parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw InputError(path, "", "output folder " + folder.string() + " does not exist; create it first");
  if (fs::is_directory(target, ec))
    throw InputError(path, "", "expected an output file path, got an existing folder");

  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw InputError(path, "", "cannot create the temporary file " + tmp + ": " + errnoText(errno));

  int err = 0;
  bool ok = writeAll(fd, content.data(), content.size(), &err);
  if (ok && durable == Durability::Synced && ::fsync(fd) != 0) {
    err = errno;
    ok = false;
  }
  if (::close(fd) != 0 && ok) {
    err = errno;
    ok = false;
  }
  if (ok && ::rename(tmp.c_str(), path.c_str()) != 0) {
    err = errno;
    ok = false;
  }
  if (!ok) {
    ::unlink(tmp.c_str());
    throw InputError(path, "", "could not write the file (" + errnoText(err) + "); any previous version is unchanged");
  }
  // Make the rename itself durable; failure here cannot un-write the file, so
  // it is not an error.
  if (durable == Durability::Unsynced) return;
  const int dfd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace fgcal::apps
