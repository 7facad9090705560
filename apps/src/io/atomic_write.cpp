// Whole-file reads and atomic writes (see results_io.hpp): every output of
// fgcal goes through writeFileAtomically, so a crash, a full disk or a
// killed process never leaves a partly written calibration behind.
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

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

// The folder a path names its file in ("." for a bare name).
fs::path folderOf(const std::string& path) {
  const fs::path folder = fs::path(path).parent_path();
  return folder.empty() ? fs::path(".") : folder;
}

// The checks before any byte is written: the folder exists, the target is not a folder.
void checkTarget(const std::string& path) {
  const fs::path target(path);
  const fs::path folder = folderOf(path);
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw InputError(path, "", "output folder " + folder.string() + " does not exist; create it first");
  if (fs::is_directory(target, ec))
    throw InputError(path, "", "expected an output file path, got an existing folder");
}

// Writes content to PATH.tmp.<pid> (fsynced when durable) and returns that
// name; on failure removes it and throws InputError naming `path`.
std::string writeTemporary(const std::string& path, const std::string& content, Durability durable) {
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
  if (!ok) {
    ::unlink(tmp.c_str());
    throw InputError(path, "", "could not write the file (" + errnoText(err) + "); any previous version is unchanged");
  }
  return tmp;
}

// Makes a rename in the folder of `path` durable; failure cannot un-write the
// file, so it is not an error.
void syncFolderOf(const std::string& path) {
  const int dfd = ::open(folderOf(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& content, Durability durable) {
  writeFilesAtomically({{path, content}}, durable);
}

void writeFilesAtomically(const std::vector<std::pair<std::string, std::string>>& files, Durability durable) {
  for (const auto& f : files) checkTarget(f.first);
  // Stage every file before any replaces its old version: a full disk or a
  // bad path leaves all of them as they were.
  std::vector<std::string> staged;
  try {
    for (const auto& f : files) staged.push_back(writeTemporary(f.first, f.second, durable));
  } catch (...) {
    for (const std::string& t : staged) ::unlink(t.c_str());
    throw;
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (::rename(staged[i].c_str(), files[i].first.c_str()) == 0) continue;
    const int err = errno;
    for (std::size_t k = i; k < staged.size(); ++k) ::unlink(staged[k].c_str());
    std::string replaced;
    for (std::size_t k = 0; k < i; ++k) replaced += (k ? ", " : "") + files[k].first;
    throw InputError(files[i].first, "",
                     "could not write the file (" + errnoText(err) + "); its previous version is unchanged" +
                         (replaced.empty() ? std::string() : " but " + replaced + " was already replaced"));
  }
  if (durable == Durability::Unsynced) return;
  for (const auto& f : files) syncFolderOf(f.first);
}

}  // namespace fgcal::apps
