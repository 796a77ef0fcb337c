#pragma once
// The known means of simple kriging and simple cokriging, one per value component, from
// KrigingOptions::simple_mean: none (0), one for every component, or one per component.

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "errfield/error.hpp"

namespace errfield::detail {

/// The `components` means given by `simple_mean` (empty: zeros; one entry: that value for all).
/// Throws ArgumentError "<who> options: simple_mean has ..." for any other length.
inline Eigen::VectorXd simple_mean_per_component(const std::vector<double>& simple_mean, int components,
                                                 const std::string& who) {
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(components);
  if (simple_mean.size() == 1) mean.setConstant(simple_mean[0]);
  else if (simple_mean.size() == static_cast<std::size_t>(components))
    for (int c = 0; c < components; ++c) mean[c] = simple_mean[static_cast<std::size_t>(c)];
  else if (!simple_mean.empty())
    throw ArgumentError(who + " options: simple_mean has " + std::to_string(simple_mean.size()) +
                        " entries; expected 0, 1 or " + std::to_string(components) + " (one per component)");
  return mean;
}

}  // namespace errfield::detail
