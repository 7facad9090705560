// Helpers shared by the kinematics tests: the shared URDF list with its
// expected facts, random joint values within limits, and a scratch folder.
#pragma once

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "fgcal/kinematics/chain.hpp"

namespace fgcal::test {

/// One row of shared/data/urdf/expected_facts.csv.
struct UrdfFacts {
  std::string file, robot_name, root_link;
  int n_links = 0, n_joints = 0, n_revolute = 0, n_continuous = 0, n_prismatic = 0, n_fixed = 0, n_leaf_links = 0;
  std::vector<std::string> feet;                   // 4 links
  std::vector<std::vector<std::string>> leg_joints;  // per foot, root -> foot
};

inline std::vector<std::string> splitBy(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(s);
  while (std::getline(in, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

inline std::vector<UrdfFacts> readExpectedFacts(const std::string& urdf_dir) {
  std::ifstream in(urdf_dir + "/expected_facts.csv");
  REQUIRE(in.good());
  std::string line;
  std::getline(in, line);  // header
  std::vector<UrdfFacts> out;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF files
    if (line.empty()) continue;
    const auto f = splitBy(line, ',');
    REQUIRE(f.size() == 12);
    UrdfFacts r;
    r.file = f[0];
    r.robot_name = f[1];
    r.root_link = f[2];
    r.n_links = std::stoi(f[3]);
    r.n_joints = std::stoi(f[4]);
    r.n_revolute = std::stoi(f[5]);
    r.n_continuous = std::stoi(f[6]);
    r.n_prismatic = std::stoi(f[7]);
    r.n_fixed = std::stoi(f[8]);
    r.n_leaf_links = std::stoi(f[9]);
    r.feet = splitBy(f[10], ' ');
    for (const auto& leg : splitBy(f[11], ' ')) r.leg_joints.push_back(splitBy(leg, '|'));
    out.push_back(r);
  }
  return out;
}

/// Uniform within the position limits; [-pi, pi] (or +-0.5 m) without limits.
inline VecX randomJointValues(const kinematics::KinematicChain& chain, std::mt19937& gen) {
  VecX q(chain.numJoints());
  for (int i = 0; i < chain.numJoints(); ++i) {
    const auto& j = chain.joints()[static_cast<std::size_t>(i)];
    double lo = j.type == kinematics::JointType::Prismatic ? -0.5 : -M_PI;
    double hi = -lo;
    if (j.limits.has_position_limits && j.limits.upper > j.limits.lower) {
      lo = j.limits.lower;
      hi = j.limits.upper;
    }
    q[i] = std::uniform_real_distribution<double>(lo, hi)(gen);
  }
  return q;
}

/// A fresh folder under the system temp dir, removed at scope exit.
struct ScratchDir {
  std::filesystem::path path;
  explicit ScratchDir(const std::string& tag) {
    path = std::filesystem::temp_directory_path() /
           ("fgcal_test_kinematics_" + tag + "_" + std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = path / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

}  // namespace fgcal::test
