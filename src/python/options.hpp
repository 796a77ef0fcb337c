#pragma once
// Option words shared by several bindings, spelled as the CLI spells them.

#include <string>

#include <Eigen/Core>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield::python {

/// Calls f.template operator()<V>() with V = double, Eigen::Vector2d or Eigen::Vector3d for 1, 2
/// or 3 value components (the value types the library's estimators are built for).
template <class F>
decltype(auto) with_components(Eigen::Index k, const char* name, F&& f) {
  switch (k) {
    case 1: return f.template operator()<double>();
    case 2: return f.template operator()<Eigen::Vector2d>();
    case 3: return f.template operator()<Eigen::Vector3d>();
    default: break;
  }
  throw ArgumentError(std::string(name) + ": " + std::to_string(k) + " value columns; expected 1, 2 or 3");
}

}  // namespace errfield::python
