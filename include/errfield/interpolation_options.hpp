#pragma once
/// @file
/// The option words of kriging and scattered IDW ("ordinary", "local", "micro", ...) mapped to
/// KrigingOptions / ScatteredIdwOptions in one place, so that `errfield interpolate`/`errfield cv`
/// and the Python module accept the same words, apply the same defaults and refuse the same
/// combinations. Use it when options arrive as text (a command line, keyword arguments); C++
/// callers building options in code set the structs directly.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "errfield/kriging.hpp"
#include "errfield/scattered_idw.hpp"

namespace errfield {

/// How the caller spells each option in error messages: "--kind" on the command line, "kind" in
/// Python. Only the names differ; the words and the rules are the same.
struct OptionNames {
  std::string kind = "kind";
  std::string mean = "mean";
  std::string backend = "backend";
  std::string neighbors = "neighbors";
  std::string radius = "radius";
  std::string neighbour_metric = "neighbour_metric";
  std::string min_neighbours = "min_neighbours";
  std::string octant_max = "octant_max";
  std::string nugget = "nugget";
  std::string duplicates = "duplicates";
  std::string power = "power";
};

/// Kriging options as words. Unset optionals take the defaults stated per field.
struct KrigingOptionText {
  /// simple | ordinary | universal | universal1 | universal2 (polynomial drift of order 1 / 2).
  std::string kind = "ordinary";
  /// Drift order 0, 1 or 2 with kind "universal" (default 1); must agree with universal1/2.
  std::optional<int> drift_order;
  /// Known mean of simple kriging, one value or one per component; required by and only allowed
  /// with kind "simple".
  std::optional<std::vector<double>> mean;
  /// dense | local | sparse; unset: local when neighbors or radius is given, else dense.
  std::optional<std::string> backend;
  /// Local back end: k nearest samples (gstat's nmax) and/or lag <= radius (gstat's maxdist). Only
  /// with the local back end, which needs at least one of them.
  std::optional<std::size_t> neighbors;
  std::optional<double> radius;
  /// Local back end: model (default: neighbours by the model's lag) | euclidean (by the plain
  /// distance of the coordinates, as gstat); see NeighbourMetric.
  std::optional<std::string> neighbour_metric;
  /// Local back end: fewer neighbours than this -> no prediction (gstat's nmin); 0 or unset = none.
  std::optional<std::size_t> min_neighbours;
  /// Local back end: at most this many neighbours per quadrant/octant (gstat's omax); 0 or unset = none.
  std::optional<std::size_t> octant_max;
  /// micro (gstat's krige: exact at the samples) | error (the nugget is measurement error).
  std::string nugget = "micro";
  /// error | average (samples closer than duplicate_distance).
  std::string duplicates = "error";
};

/// A kriging kind with its polynomial drift order (meaningful for Universal only).
struct KrigingKindChoice {
  KrigingKind kind = KrigingKind::Ordinary;
  int drift_order = 1;
};

/// simple | ordinary | universal (drift_order, default 1) | universal1 | universal2. Throws
/// ArgumentError naming names.kind for another word or a drift order contradicting universal1/2.
KrigingKindChoice kriging_kind_from_text(const std::string& kind, std::optional<int> drift_order,
                                         const OptionNames& names = {});

/// The KrigingOptions the words select (other fields at their defaults), validated.
/// Throws ArgumentError naming the option as `names` spells it, the word given and those accepted.
KrigingOptions kriging_options_from_text(const KrigingOptionText& text, const OptionNames& names = {});

/// Scattered IDW options as words/numbers; unset: power 2 (gstat's idw), all neighbours, no radius.
struct ScatteredIdwOptionText {
  std::optional<double> power;
  std::optional<std::size_t> neighbors;
  std::optional<double> radius;
};

/// The ScatteredIdwOptions selected (other fields at their defaults), validated; errors name the
/// option as `names` spells it.
ScatteredIdwOptions scattered_idw_options_from_text(const ScatteredIdwOptionText& text, const OptionNames& names = {});

}  // namespace errfield
