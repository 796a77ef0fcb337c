#pragma once
// SIMULATED readings of three reflector nests on one UR5e flange plate, and the models the tool-point
// tests (issue 47) score: not the built-in set-up (another robot, scattered poses with tool
// orientations within 30 deg, other nest positions). Made once per test suite in a directory the
// suite owns.
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "support/cli_harness.hpp"

namespace errfield::testing::three_nest {

namespace fs = std::filesystem;

/// The nests (flange frame, mm) as `simulate --reflectors` takes them; r1 is the robot JSON's tool.
inline constexpr const char* kNests = "0,0,60;110,0,60;0,100,60";
/// Poses: the first kTrainPoses are training poses, the rest held out.
inline constexpr std::size_t kPoses = 150, kTrainPoses = 110;

/// Rows of `source` (nests.csv) whose reflector is in `labels` and whose pose is (not) a training pose, at most
/// `limit` of them (0: all), written to `out` in `dir`.
/// Without x,y,z (`with_xyz` false) the nominal positions are the FK of the robot given, as in real
/// data whose robot JSON lacks the tool.
inline void write_subset(const fs::path& dir, const std::string& out, const std::set<std::string>& labels, bool training,
                         std::size_t limit = 0, const std::string& source = "nests.csv", bool with_xyz = true) {
  const CsvTable all = CsvTable::read((dir / source).string());
  const std::size_t point = all.column_index("point"), reflector = all.column_index("reflector");
  std::vector<std::string> poses;
  for (std::size_t i = 0; i < all.row_count(); ++i)
    if (poses.empty() || poses.back() != all.cell(i, point)) poses.emplace_back(all.cell(i, point));
  const std::set<std::string> train(poses.begin(), poses.begin() + static_cast<std::ptrdiff_t>(kTrainPoses));
  auto kept = [&](std::size_t c) {
    const std::string& h = all.header()[c];
    return with_xyz || (h != "x" && h != "y" && h != "z");
  };
  std::string text;
  for (std::size_t c = 0; c < all.header().size(); ++c)
    if (kept(c)) text += (text.empty() ? "" : ",") + all.header()[c];
  text += "\n";
  std::size_t taken = 0;
  for (std::size_t i = 0; i < all.row_count(); ++i) {
    if (!labels.count(std::string(all.cell(i, reflector))) || train.count(std::string(all.cell(i, point))) != (training ? 1u : 0u))
      continue;
    if (limit && taken == limit) break;
    ++taken;
    std::string line;
    for (std::size_t c = 0; c < all.header().size(); ++c)
      if (kept(c)) line += (line.empty() ? "" : ",") + std::string(all.cell(i, c));
    text += line + "\n";
  }
  std::ofstream(dir / out, std::ios::binary) << text;
}

/// Simulates `out` (nests.csv) and ur5e.json (the simulated robot's nominal description) in `dir`,
/// with further simulate `options` (e.g. --config of another unit).
inline void simulate(const fs::path& dir, int seed = 7, const std::string& out = "nests.csv", const std::string& options = "") {
  const CliResult r = run_errfield_line("simulate " + options + " --robot ur5e --seed " + std::to_string(seed) + " --sample scattered:" +
                                            std::to_string(kPoses) + " --orientation-spread 30 --measure positions --reflectors \"" +
                                            kNests + "\" --robot-out ur5e.json --out " + out,
                                        dir);
  ASSERT_EQ(r.exit_code, 0) << r.output();
}

/// ur5e.json with its tool at (x, y, z) mm and no tool rotation, as `name`.
inline void write_robot_with_tool(const fs::path& dir, const std::string& name, double x, double y, double z) {
  nlohmann::json robot = nlohmann::json::parse(ScratchDir::slurp(dir / "ur5e.json"));
  robot["tool"] = {{"x_mm", x}, {"y_mm", y}, {"z_mm", z}, {"rx_deg", 0.0}, {"ry_deg", 0.0}, {"rz_deg", 0.0}};
  std::ofstream(dir / name, std::ios::binary) << robot.dump();
}

}  // namespace errfield::testing::three_nest
