// The paper's interpolation rule (SPEC §5, eqs. 19-21): distance errors measured at the nodes of a
// 500 mm cube with a 125 mm step (5 x 5 x 5 nodes), interpolated to arbitrary targets from the 8
// vertices of each target's cell with weights 1/d. The "measurements" are simulated.
#include <cstdio>
#include <vector>

#include "errfield/grid_idw.hpp"

int main() {
  using namespace errfield;
  const RegularGrid3 grid(/*origin mm*/ {1200, -250, 300}, /*step mm*/ {125, 125, 125}, /*nodes*/ {5, 5, 5});

  // Simulated distance error (mm) at every node: a smooth function of position.
  std::vector<double> dL(grid.node_count());
  for (std::size_t n = 0; n < dL.size(); ++n) {
    const Eigen::Vector3d p = grid.node_position(n);
    dL[n] = 0.3 + 4e-4 * (p.x() - 1200) - 2e-4 * p.y() + 1e-4 * p.z();
  }

  GridIdwOptions options;  // power 1 as in the paper; targets outside the grid are an error
  const GridIdw<double> idw(grid, std::span<const double>(dL), options);

  const std::vector<Eigen::Vector3d> targets{{1262.5, -187.5, 362.5}, {1500, 0, 500}, {1333, 77, 641}};
  const std::vector<double> predicted = idw.predict(std::span<const Eigen::Vector3d>(targets));
  for (std::size_t i = 0; i < targets.size(); ++i)
    std::printf("target (%g, %g, %g) mm: predicted dL = %.4f mm\n", targets[i].x(), targets[i].y(), targets[i].z(),
                predicted[i]);

  // A target outside the grid: an OutsideGridError naming it and the grid bounds.
  try {
    idw({1000, 0, 400});
  } catch (const OutsideGridError& e) {
    std::printf("as expected: %s\n", e.what());
  }
  return 0;
}
