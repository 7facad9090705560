// Regression runner for the fuzz targets, built in the normal (gcc) build and
// run by ctest: feeds every file of the folders (or files) given on the
// command line to the target's LLVMFuzzerTestOneInput, one by one, in name
// order. The seed corpus (fuzz/corpus/<target>/) and every input that once
// crashed a target (fuzz/regressions/<target>/) stay tested without clang.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
extern "C" __attribute__((weak)) int LLVMFuzzerInitialize(int* argc, char*** argv);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (LLVMFuzzerInitialize) LLVMFuzzerInitialize(&argc, &argv);
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path p(argv[i]);
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
    } else if (fs::is_regular_file(p, ec)) {
      files.push_back(p);
    } else {
      std::fprintf(stderr, "regression runner: %s: no such file or folder\n", argv[i]);
      return 2;
    }
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "  %s (%zu bytes)\n", f.string().c_str(), bytes.size());
    std::vector<uint8_t> copy(bytes.begin(), bytes.end());  // exact-size buffer, so ASan sees overreads
    LLVMFuzzerTestOneInput(copy.data(), copy.size());
  }
  std::fprintf(stderr, "regression runner: %zu input(s) passed\n", files.size());
  return files.empty() ? 1 : 0;
}
