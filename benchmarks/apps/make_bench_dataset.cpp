// make_bench_dataset: a simulated dataset folder of a given number of images,
// at a given resolution, for the bag benchmark (run_bag_benchmark.sh), which
// turns it into a ROS 1 bag with ROS's own writer and calibrates from both.
//
//   make_bench_dataset --out DIR --frames N [--width 320 --height 240] [--seed 11]
//                      [--distinct K] [--overwrite]
//
// N is the number of cam0 instants of the default 2-camera rig (cam0 at 30 Hz,
// cam1 at 15 Hz: 1.5 images per instant). `fgcal simulate` renders at each
// camera's own resolution (1024x544, 640x480); this renders at WxH with one
// sample per pixel so that tens of thousands of images stay affordable.
//
// --distinct K (default 0: every instant rendered) renders only K instants and
// repeats that recording until it holds N instants: each repetition hard-links
// the image files under stamps shifted by the recording's length and appends
// the joint samples shifted the same way (as bench_long_run does). The
// repeated images are then identical files on disk; a bag made from the folder
// still stores every message in full.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "fgcal/apps/simulator.hpp"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  std::string out;
  int frames = 0, width = 320, height = 240, distinct = 0;
  unsigned seed = 11;
  bool overwrite = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "make_bench_dataset: " << a << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--out") out = next();
    else if (a == "--frames") frames = std::stoi(next());
    else if (a == "--width") width = std::stoi(next());
    else if (a == "--height") height = std::stoi(next());
    else if (a == "--seed") seed = static_cast<unsigned>(std::stoul(next()));
    else if (a == "--distinct") distinct = std::stoi(next());
    else if (a == "--overwrite") overwrite = true;
    else {
      std::cerr << "usage: make_bench_dataset --out DIR --frames N [--width W --height H] [--seed S] "
                   "[--distinct K] [--overwrite]\n";
      return 2;
    }
  }
  if (out.empty() || frames < 1 || distinct < 0) {
    std::cerr << "make_bench_dataset: --out DIR and --frames N >= 1 are required (--distinct >= 0)\n";
    return 2;
  }
  try {
    const bool repeat = distinct > 0 && distinct < frames;
    const fs::path dir(out);
    const fs::path base = repeat ? fs::path(out + ".base") : dir;
    if (overwrite) fs::remove_all(dir), fs::remove_all(base);

    fgcal::apps::SimulationOptions sim;
    sim.out_dir = base.string();
    sim.frames = repeat ? distinct : frames;
    sim.cameras = 2;
    sim.seed = seed;
    sim.supersampling = 1;
    sim.image_width = width;
    sim.image_height = height;
    sim.progress = [](const std::string& cam, int done, int total) {
      if (done % 1000 == 0 || done == total) std::fprintf(stderr, "  %s %d/%d\r", cam.c_str(), done, total);
    };
    const auto s = fgcal::apps::simulateDataset(sim);
    std::fprintf(stderr, "\nsimulated %d images (%d instants, %dx%d) in %.0f s\n", s.images_written, s.instants, width,
                 height, s.seconds);
    if (!repeat) {
      std::printf("%s: %d images\n", out.c_str(), s.images_written);
      return 0;
    }

    std::ifstream jin(base / "joints.csv");
    std::string header;
    std::getline(jin, header);
    std::vector<std::pair<long long, std::string>> rows;  // stamp, rest of the line
    for (std::string l; std::getline(jin, l);) {
      if (l.empty()) continue;
      const auto comma = l.find(',');
      rows.emplace_back(std::stoll(l.substr(0, comma)), l.substr(comma));
    }
    const long long period = rows.back().first - rows.front().first + 1000000;  // + 1 ms
    const int reps = (frames + distinct - 1) / distinct;
    fs::create_directories(dir);
    for (const char* f : {"rig.yaml", "robot.urdf", "ground_truth.yaml"})
      fs::copy_file(base / f, dir / f, fs::copy_options::overwrite_existing);
    {
      std::ofstream jout(dir / "joints.csv");
      jout << header << "\n";
      for (int r = 0; r < reps; ++r)
        for (const auto& [stamp, rest] : rows) jout << stamp + r * period << rest << "\n";
    }
    long linked = 0;
    for (const auto& cam : s.cameras) {
      fs::create_directories(dir / cam);
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(base / cam)) files.push_back(e.path());
      for (int r = 0; r < reps; ++r)
        for (const auto& f : files) {
          const long long stamp = std::stoll(f.stem().string()) + r * period;
          fs::create_hard_link(f, dir / cam / (std::to_string(stamp) + f.extension().string()));
          ++linked;
        }
    }
    std::printf("%s: %ld images (%d x %d distinct)\n", out.c_str(), linked, reps, s.images_written);
  } catch (const std::exception& e) {
    std::cerr << "make_bench_dataset: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
