#pragma once
// Option words shared by several bindings, spelled as the CLI spells them.

#include <string>

#include <Eigen/Core>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield::python {

struct KindChoice {
  KrigingKind kind = KrigingKind::Ordinary;
  int drift_order = 1;
};

/// 'simple' | 'ordinary' | 'universal' (with drift_order) | 'universal1' | 'universal2' (the CLI's --kind).
inline KindChoice kriging_kind_arg(const std::string& kind, int drift_order) {
  KindChoice k;
  k.drift_order = drift_order;
  if (kind == "simple") k.kind = KrigingKind::Simple;
  else if (kind == "ordinary") k.kind = KrigingKind::Ordinary;
  else if (kind == "universal") k.kind = KrigingKind::Universal;
  else if (kind == "universal1" || kind == "universal2") {
    k.kind = KrigingKind::Universal;
    k.drift_order = kind == "universal1" ? 1 : 2;
  } else {
    throw ArgumentError("kind: '" + kind + "'; expected 'simple', 'ordinary', 'universal', 'universal1' or 'universal2'");
  }
  return k;
}

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
