// Prints the Eigen alignment this translation unit compiles fgcal's headers
// with. The library's own objects were compiled with the package's: the two
// must agree, or a structure holding a fixed-size matrix (a Mat6 of a noise
// model, an SE3) is laid out differently on the two sides of the headers, and
// a matrix allocated on one side is freed by another allocator on the other.
#include <cstdio>

#include <fgcal/core/types.hpp>

int main() {
  std::printf("eigen alignment %d (alignof Mat6 %zu, heap by malloc %d)\n", EIGEN_MAX_STATIC_ALIGN_BYTES,
              alignof(fgcal::Mat6), EIGEN_MALLOC_ALREADY_ALIGNED);
  return 0;
}
