// joints.csv: reading, every error with its line (and column), NaN handling,
// column checks against a chain, interpolation and the exact write round trip.
#include <chrono>
#include <cmath>

#include <catch2/catch.hpp>

#include "apps_test_util.hpp"
#include "fgcal/apps/joints_csv.hpp"
#include "fgcal/kinematics/default_robot.hpp"

using namespace fgcal;
using namespace fgcal::apps;
using namespace fgcal::apps::test;

namespace {
JointLog parse(const std::string& text) { return parseJointsCsv(text, "joints.csv"); }
const std::string kCsv =
    "stamp_ns,a,b,c\n"
    "1000,0.0,1.0,-1.0\n"
    "2000,1.0,3.0,-1.0\n"
    "4000,2.0,nan,1.0\n";
}  // namespace

TEST_CASE("joints.csv: a valid file", "[apps][joints]") {
  const JointLog log = parse(kCsv);
  CHECK(log.names == std::vector<std::string>{"a", "b", "c"});
  CHECK(log.stamps_ns == std::vector<int64_t>{1000, 2000, 4000});
  REQUIRE(log.positions.rows() == 3);
  REQUIRE(log.positions.cols() == 3);
  CHECK(log.positions(1, 1) == 3.0);
  CHECK(std::isnan(log.positions(2, 1)));
  CHECK(log.column("c") == 2);
  CHECK(log.column("z") == -1);
  REQUIRE(log.warnings.size() == 1);
  CHECK_THAT(log.warnings[0], Catch::Contains("1 NaN/inf") && Catch::Contains("b 1"));
}

TEST_CASE("joints.csv: tolerated variations", "[apps][joints]") {
  SECTION("CRLF, spaces, blank lines, BOM, no final newline") {
    const JointLog log = parse("\xEF\xBB\xBFstamp_ns, a ,b\r\n\r\n10, 1.5 ,+2\r\n20,3,4e-3");
    CHECK(log.names == std::vector<std::string>{"a", "b"});
    CHECK(log.stamps_ns == std::vector<int64_t>{10, 20});
    CHECK(log.positions(0, 0) == 1.5);
    CHECK(log.positions(0, 1) == 2.0);
    CHECK(log.positions(1, 1) == 4e-3);
  }
  SECTION("inf, -inf, NaN and empty fields are kept as NaN and counted") {
    const JointLog log = parse("stamp_ns,a,b\n1,inf,-inf\n2,NaN,\n3,0,0\n");
    CHECK(std::isnan(log.positions(0, 0)));
    CHECK(std::isnan(log.positions(0, 1)));
    CHECK(std::isnan(log.positions(1, 0)));
    CHECK(std::isnan(log.positions(1, 1)));
    REQUIRE(log.warnings.size() == 1);
    CHECK_THAT(log.warnings[0], Catch::Contains("4 NaN/inf/empty values") && Catch::Contains("1 of them empty"));
  }
  SECTION("negative stamps") {
    CHECK(parse("stamp_ns,a\n-5,0\n0,1\n").stamps_ns == std::vector<int64_t>{-5, 0});
  }
}

TEST_CASE("joints.csv: every error names the file and line", "[apps][joints]") {
  TempDir tmp;
  CHECK_INPUT_ERROR(loadJointsCsv(tmp / "joints.csv"), "joints.csv", "", "not found");
  writeFile(tmp / "joints.csv", "");
  CHECK_INPUT_ERROR(loadJointsCsv(tmp / "joints.csv"), "joints.csv", "line 1", "empty file");
  CHECK_INPUT_ERROR(parse("\n  \n"), "joints.csv", "line 1", "expected the header", "empty file");
  CHECK_INPUT_ERROR(parse("time,a,b\n1,2,3\n"), "joints.csv", "line 1", "stamp_ns as first column", "'time,a,b'");
  CHECK_INPUT_ERROR(parse("1000,0.1,0.2\n2000,0.1,0.2\n"), "joints.csv", "line 1", "expected the header");
  CHECK_INPUT_ERROR(parse("stamp_ns\n1\n"), "joints.csv", "line 1", "at least one joint column");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b,a\n1,2,3,4\n"), "joints.csv", "line 1", "unique column names",
                    "'a' twice (columns 2 and 4)");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,,b\n1,2,3,4\n"), "joints.csv", "line 1", "empty one");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1,2,3\n2,3\n"), "joints.csv", "line 3", "expected 3 comma-separated fields",
                    "got 2");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1,2,3\n2,3,4,5\n"), "joints.csv", "line 3", "got 4");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1,2,3\n2,3,abc\n"), "joints.csv", "line 3, column b",
                    "expected a number", "'abc'");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1,2,3\n2,0x1,4\n"), "joints.csv", "line 3, column a", "'0x1'");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1.5e9,2,3\n"), "joints.csv", "line 2, column stamp_ns",
                    "integer time stamp in nanoseconds", "'1.5e9'");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n99999999999999999999,2,3\n"), "joints.csv", "line 2, column stamp_ns",
                    "integer");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1,2,3\n2,2,3\n2,2,3\n"), "joints.csv", "line 4, column stamp_ns",
                    "strictly increasing", "got 2 again");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n1,2,3\n\n5,2,3\n3,2,3\n"), "joints.csv", "line 5", "got 3 after 5");
  CHECK_INPUT_ERROR(parse("stamp_ns,a,b\n"), "joints.csv", "line 1", "at least one data row");
}

TEST_CASE("joints.csv: columns against a kinematic chain", "[apps][joints]") {
  const auto robot = kinematics::loadDefaultRobot();
  const auto chain_joints = robot.chainJointNames("base_link", "lf_foot");
  REQUIRE(chain_joints.size() == 3);

  SECTION("all present, extra columns give one warning naming them") {
    const JointLog log = parse("stamp_ns,rf_haa_joint,lf_haa_joint,lf_hfe_joint,lf_kfe_joint,rf_hfe_joint\n1,0,0,0,0,0\n");
    const auto w = checkColumns(log, chain_joints, "joints.csv");
    REQUIRE(w.size() == 1);
    CHECK_THAT(w[0], Catch::Contains("joints.csv") && Catch::Contains("2 columns") &&
                         Catch::Contains("rf_haa_joint, rf_hfe_joint"));
    CHECK(columnIndices(log, chain_joints, "joints.csv") == std::vector<int>{1, 2, 3});
  }
  SECTION("exactly the chain: no warning") {
    const JointLog log = parse("stamp_ns,lf_kfe_joint,lf_hfe_joint,lf_haa_joint\n1,0,0,0\n");
    CHECK(checkColumns(log, chain_joints, "joints.csv").empty());
    CHECK(columnIndices(log, chain_joints, "joints.csv") == std::vector<int>{2, 1, 0});
  }
  SECTION("missing ones are all listed, with the columns present") {
    const JointLog log = parse("stamp_ns,lf_hfe_joint,rf_kfe_joint\n1,0,0\n");
    CHECK_INPUT_ERROR(checkColumns(log, chain_joints, "data/joints.csv"), "data/joints.csv", "header",
                      "missing 2 of 3: lf_haa_joint, lf_kfe_joint", "the file has: stamp_ns, lf_hfe_joint, rf_kfe_joint");
  }
}

TEST_CASE("joints.csv: interpolation", "[apps][joints]") {
  const JointLog log = parse(kCsv);
  const std::vector<int> ac{0, 2}, all{0, 1, 2};
  std::string why;
  SECTION("exact at samples, including the first and last") {
    for (int i = 0; i < 3; ++i) {
      const auto q = interpolate(log, log.stamps_ns[static_cast<std::size_t>(i)], ac, &why);
      REQUIRE(q);
      CHECK((*q)[0] == log.positions(i, 0));
      CHECK((*q)[1] == log.positions(i, 2));
    }
  }
  SECTION("linear between samples") {
    const auto q = interpolate(log, 1250, all, &why);
    REQUIRE(q);
    CHECK((*q)[0] == Approx(0.25));
    CHECK((*q)[1] == Approx(1.5));
    CHECK((*q)[2] == Approx(-1.0));
    const auto r = interpolate(log, 3000, ac, &why);
    REQUIRE(r);
    CHECK((*r)[0] == Approx(1.5));
    CHECK((*r)[1] == Approx(0.0).margin(1e-15));
  }
  SECTION("NaN in a used joint makes the stamp unusable; unused joints do not matter") {
    JointLookupFailure failure = JointLookupFailure::OutsideSpan;
    CHECK_FALSE(interpolate(log, 3000, all, &why, &failure));
    CHECK(why == "NaN/inf in joint b near stamp 3000");
    CHECK(failure == JointLookupFailure::NotFinite);  // an image's status reads this, not the text
    CHECK_FALSE(interpolate(log, 4000, {1}, &why));
    CHECK(interpolate(log, 1500, {1}, &why));  // the NaN is in the next interval only
  }
  SECTION("outside the recorded span") {
    JointLookupFailure failure = JointLookupFailure::NotFinite;
    CHECK_FALSE(interpolate(log, 999, ac, &why, &failure));
    CHECK_THAT(why, Catch::StartsWith("outside the recorded span") && Catch::Contains("[1000, 4000]"));
    CHECK(failure == JointLookupFailure::OutsideSpan);
    CHECK_FALSE(interpolate(log, 4001, ac, nullptr));
  }
  SECTION("large log: binary search stays correct and fast") {
    const int n = 200000;
    std::vector<int64_t> st(n);
    Eigen::MatrixXd pos(n, 1);
    for (int i = 0; i < n; ++i) {
      st[static_cast<std::size_t>(i)] = 1000LL * i + 7;
      pos(i, 0) = 0.5 * i;
    }
    const JointLog big = parse(formatJointsCsv({"j"}, st, pos));
    const auto t0 = std::chrono::steady_clock::now();
    double err = 0.0;
    for (int k = 0; k < 100000; ++k) {
      const int64_t s = 7 + (static_cast<int64_t>(k) * 1999937LL) % (1000LL * (n - 1));
      const auto q = interpolate(big, s, {0});
      REQUIRE(q);
      err = std::max(err, std::abs((*q)[0] - 0.5 * static_cast<double>(s - 7) / 1000.0));
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    CHECK(err < 1e-9);
    CHECK(secs < 1.0);  // 1e5 queries; a linear scan would take minutes
  }
}

TEST_CASE("joints.csv: write -> read is exact", "[apps][joints]") {
  TempDir tmp;
  const std::vector<std::string> names{"lf_haa_joint", "lf_hfe_joint", "lf_kfe_joint"};
  const std::vector<int64_t> stamps{1700000000000000000LL, 1700000000001000000LL, 1700000000002000001LL};
  Eigen::MatrixXd pos(3, 3);
  pos << 0.1 + 0.2, -1.0 / 3.0, 1e-300,  //
      M_PI, std::nan(""), -0.0,            //
      123456.789012345678, 5e-324, -2.5;
  writeJointsCsv(tmp / "joints.csv", names, stamps, pos);
  const JointLog log = loadJointsCsv(tmp / "joints.csv");
  CHECK(log.names == names);
  CHECK(log.stamps_ns == stamps);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      if (std::isnan(pos(r, c)))
        CHECK(std::isnan(log.positions(r, c)));
      else
        CHECK(log.positions(r, c) == pos(r, c));
    }
  CHECK_INPUT_ERROR(writeJointsCsv(tmp / "bad.csv", names, stamps, Eigen::MatrixXd(2, 3)), "joints.csv", "",
                    "3 x 3", "got 2 x 3");
  CHECK_FALSE(fs::exists(tmp / "bad.csv"));
}

namespace {

/// interpolate() on `part` equals interpolate() on `whole` at `stamp`: the
/// same positions bit for bit, or the same reason why not.
void checkSameInterpolation(const JointLog& whole, const JointLog& part, int64_t stamp,
                            const std::vector<std::string>& joints) {
  INFO("stamp " << stamp);
  std::string why_whole, why_part;
  const auto a = interpolate(whole, stamp, columnIndices(whole, joints, "whole"), &why_whole);
  const auto b = interpolate(part, stamp, columnIndices(part, joints, "part"), &why_part);
  REQUIRE(a.has_value() == b.has_value());
  if (a) CHECK(*a == *b);
  CHECK(why_whole == why_part);
}

/// A log of `rows` samples 1 ms apart from stamp 1000, columns a..e, with
/// NaN scattered in; as CSV text.
std::string bigLog(int rows) {
  std::string s = "stamp_ns,a,b,c,d,e\n";
  for (int r = 0; r < rows; ++r) {
    s += std::to_string(1000 + 1000000LL * r);
    for (int c = 0; c < 5; ++c) s += (r % 97 == 13 && c == 2) ? ",nan" : "," + std::to_string(0.001 * r * (c + 1) - c);
    s += "\n";
  }
  return s;
}

}  // namespace

TEST_CASE("joints.csv through a filter: the chain's joints around the images' stamps, the same interpolation",
          "[apps][joints]") {
  const std::string text = bigLog(2000);
  const JointLog whole = parse(text);
  // Image stamps: before the first sample, on samples, between them, next to
  // the NaN rows, on the last, after it; sorted, some repeated.
  std::vector<int64_t> stamps{0, 1000, 1000, 2500000, 13001000, 13500000, 14000999, 1000001000, 1999001000,
                              1999001001, 5000000000};
  for (int k = 0; k < 50; ++k) stamps.push_back(37 + 39000017LL * k);
  std::sort(stamps.begin(), stamps.end());
  const std::vector<std::string> joints{"d", "c"};
  JointLogFilter filter;
  filter.columns = joints;
  filter.around_stamps_ns = &stamps;
  const JointLog part = parseJointsCsv(text, "joints.csv", &filter);
  CHECK(part.names == joints);
  CHECK(part.source_names == whole.names);
  CHECK(part.source_samples == 2000);
  CHECK(part.warnings == whole.warnings);  // counted over every column and row all the same
  CHECK(part.stamps_ns.size() < 160);      // at most two a stamp, and the ends
  CHECK(part.stamps_ns.front() == whole.stamps_ns.front());
  CHECK(part.stamps_ns.back() == whole.stamps_ns.back());
  for (int64_t s : stamps) checkSameInterpolation(whole, part, s, joints);
  // The same selection of a log in memory (a bag's joint table).
  const JointLog again = filterJointLog(whole, filter, "joints.csv");
  CHECK(again.stamps_ns == part.stamps_ns);
  CHECK(again.names == part.names);
  CHECK(((again.positions.array() == part.positions.array()) ||
         (again.positions.array().isNaN() && part.positions.array().isNaN())).all());
  for (int64_t s : stamps) checkSameInterpolation(whole, again, s, joints);
  // Columns only: every sample.
  JointLogFilter columns_only;
  columns_only.columns = {"e"};
  CHECK(parseJointsCsv(text, "joints.csv", &columns_only).stamps_ns == whole.stamps_ns);
}

TEST_CASE("joints.csv through a filter: a chain joint without a column is the error columnIndices gives",
          "[apps][joints]") {
  JointLogFilter filter;
  filter.columns = {"a", "zz", "yy"};
  CHECK_INPUT_ERROR(parseJointsCsv(kCsv, "joints.csv", &filter), "joints.csv", "line 1 (header)", "missing 2 of 3",
                    "zz, yy", "stamp_ns, a, b, c");
  CHECK_INPUT_ERROR(filterJointLog(parse(kCsv), filter, "joints.csv"), "joints.csv", "line 1 (header)",
                    "missing 2 of 3", "stamp_ns, a, b, c");
}

TEST_CASE("joints.csv: read from the file in blocks, the same as from its text", "[apps][joints]") {
  TempDir tmp;
  const std::string text = bigLog(40000);  // more than one read block
  REQUIRE(text.size() > (2u << 20));
  writeFile(tmp / "joints.csv", text);
  const JointLog a = loadJointsCsv(tmp / "joints.csv"), b = parse(text);
  CHECK(a.names == b.names);
  CHECK(a.stamps_ns == b.stamps_ns);
  CHECK(a.warnings.size() == 1);
  CHECK(a.positions.rows() == b.positions.rows());
  CHECK((a.positions.array() == b.positions.array() || (a.positions.array().isNaN() && b.positions.array().isNaN()))
            .all());
  // A last line without its newline, and an error on a line past the first block, with its number.
  writeFile(tmp / "cut.csv", text.substr(0, text.size() - 1));
  CHECK(loadJointsCsv(tmp / "cut.csv").stamps_ns == b.stamps_ns);
  std::string bad = text;
  bad.replace(bad.rfind(',') + 1, 1, "x");
  writeFile(tmp / "bad.csv", bad);
  CHECK_INPUT_ERROR(loadJointsCsv(tmp / "bad.csv"), "bad.csv", "line 40001, column e", "expected a number");
}
