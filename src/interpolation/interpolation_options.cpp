// Text -> KrigingOptions / ScatteredIdwOptions, shared by the CLI and the Python module.

#include "errfield/interpolation_options.hpp"

#include <cmath>
#include <tuple>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {

namespace {

std::string quoted(const std::string& word) { return "'" + word + "'"; }

}  // namespace

KrigingKindChoice kriging_kind_from_text(const std::string& kind, std::optional<int> drift_order,
                                         const OptionNames& n) {
  KrigingKindChoice c;
  if (kind == "simple") c.kind = KrigingKind::Simple;
  else if (kind == "ordinary") c.kind = KrigingKind::Ordinary;
  else if (kind == "universal" || kind == "universal1" || kind == "universal2") c.kind = KrigingKind::Universal;
  else
    throw ArgumentError(n.kind + " is " + quoted(kind) +
                        "; expected simple, ordinary, universal1, universal2 or universal (with a drift order)");
  if (c.kind == KrigingKind::Universal) {
    const int implied = kind == "universal2" ? 2 : 1;
    if (drift_order && kind != "universal" && *drift_order != implied)
      throw ArgumentError("drift order " + std::to_string(*drift_order) + " contradicts " + n.kind + " " + kind);
    c.drift_order = kind == "universal" ? drift_order.value_or(1) : implied;
  }
  return c;
}

KrigingOptions kriging_options_from_text(const KrigingOptionText& t, const OptionNames& n) {
  KrigingOptions o;
  const KrigingKindChoice kind = kriging_kind_from_text(t.kind, t.drift_order, n);
  o.kind = kind.kind;
  o.drift_order = kind.drift_order;

  if (o.kind == KrigingKind::Simple) {
    if (!t.mean || t.mean->empty()) throw ArgumentError(n.kind + " simple needs the known mean (" + n.mean + ")");
    for (double m : *t.mean)
      if (!std::isfinite(m)) throw ArgumentError(n.mean + " is " + format_number(m) + "; expected a finite number");
    o.simple_mean = *t.mean;
  } else if (t.mean) {
    throw ArgumentError(n.mean + " applies to " + n.kind + " simple only (ordinary and universal kriging estimate the mean)");
  }

  const bool neighbourhood = t.neighbors.has_value() || t.radius.has_value();
  if (!t.backend) o.backend = neighbourhood ? KrigingBackend::Local : KrigingBackend::Dense;
  else o.backend = kriging_backend_from_name(*t.backend);
  if (o.backend != KrigingBackend::Local && neighbourhood)
    throw ArgumentError(n.neighbors + "/" + n.radius + " select the neighbourhood of " + n.backend + " local, not " +
                        n.backend + " " + *t.backend);
  if (o.backend == KrigingBackend::Local) {
    if (!neighbourhood) throw ArgumentError(n.backend + " local needs " + n.neighbors + " K and/or " + n.radius + " R");
    o.neighbors = t.neighbors.value_or(0);
    if (t.radius) {
      if (!(*t.radius > 0.0))
        throw ArgumentError(n.radius + " is " + format_number(*t.radius) + "; expected a value > 0");
      o.radius = *t.radius;
    }
  }
  if (t.neighbour_metric) {
    if (o.backend != KrigingBackend::Local)
      throw ArgumentError(n.neighbour_metric + " chooses the neighbours of " + n.backend + " local (with " + n.neighbors +
                          " or " + n.radius + ")");
    if (*t.neighbour_metric == "model") o.neighbour_metric = NeighbourMetric::Model;
    else if (*t.neighbour_metric == "euclidean") o.neighbour_metric = NeighbourMetric::Euclidean;
    else throw ArgumentError(n.neighbour_metric + " is " + quoted(*t.neighbour_metric) + "; expected model or euclidean");
  }

  for (const auto& [value, name, field] :
       {std::tuple{t.min_neighbours, n.min_neighbours, &o.min_neighbours}, std::tuple{t.octant_max, n.octant_max, &o.octant_max}}) {
    if (!value || *value == 0) continue;
    if (o.backend != KrigingBackend::Local)
      throw ArgumentError(name + " applies to the neighbourhood of " + n.backend + " local (with " + n.neighbors + " or " +
                          n.radius + ")");
    *field = *value;
  }

  if (t.nugget == "micro") o.nugget = NuggetTreatment::MicroScale;
  else if (t.nugget == "error") o.nugget = NuggetTreatment::MeasurementError;
  else throw ArgumentError(n.nugget + " is " + quoted(t.nugget) + "; expected micro or error");
  if (t.duplicates == "error" || t.duplicates == "refuse") o.duplicates = DuplicatePolicy::Error;
  else if (t.duplicates == "average") o.duplicates = DuplicatePolicy::Average;
  else throw ArgumentError(n.duplicates + " is " + quoted(t.duplicates) + "; expected refuse (or error) or average");
  o.validate();
  return o;
}

ScatteredIdwOptions scattered_idw_options_from_text(const ScatteredIdwOptionText& t, const OptionNames& n) {
  ScatteredIdwOptions o;
  if (t.power) {
    if (!(*t.power >= 0.0) || !std::isfinite(*t.power))
      throw ArgumentError(n.power + " is " + format_number(*t.power) + "; expected a finite value >= 0");
    o.power = *t.power;
  }
  o.neighbors = t.neighbors.value_or(0);
  if (t.radius) {
    if (!(*t.radius > 0.0)) throw ArgumentError(n.radius + " is " + format_number(*t.radius) + "; expected a value > 0");
    o.radius = *t.radius;
  }
  o.validate();
  return o;
}

}  // namespace errfield
