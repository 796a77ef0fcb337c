#include "errfield/anisotropy.hpp"

#include <charconv>
#include <cmath>
#include <numbers>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {
namespace {

double radians(double deg) { return deg * std::numbers::pi / 180.0; }

void check_positive(double v, const std::string& what) {
  if (!(v > 0.0) || !std::isfinite(v))
    throw ArgumentError("anisotropy: " + what + " = " + format_number(v) + "; expected a finite value > 0");
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

}  // namespace

Anisotropy Anisotropy::ard(std::vector<double> range_multipliers) {
  if (range_multipliers.empty()) throw ArgumentError("anisotropy: ard() needs one range multiplier per coordinate");
  Anisotropy a;
  a.type_ = Type::Ard;
  a.dimension_ = static_cast<int>(range_multipliers.size());
  // Only the diagonal: a D x D matrix would let a long text ask for D^2 doubles.
  const std::size_t d = range_multipliers.size();
  a.matrix_.assign(d, 0.0);
  for (std::size_t k = 0; k < d; ++k) {
    check_positive(range_multipliers[k], "ard multiplier of coordinate " + std::to_string(k + 1));
    a.matrix_[k] = 1.0 / range_multipliers[k];
  }
  a.parameters_ = std::move(range_multipliers);
  return a;
}

Anisotropy Anisotropy::rotated(std::vector<double> g) {
  Anisotropy a;
  a.type_ = Type::Rotated;
  for (double v : g)
    if (!std::isfinite(v)) throw ArgumentError("anisotropy: anis() has a non-finite number");
  if (g.size() == 2) {
    // Rows: the unit vector of the major axis (angle clockwise from +y), then the one across it
    // divided by the ratio, so that a lag `ratio * range` across counts as `range`.
    check_positive(g[1], "anis ratio");
    const double t = radians(g[0]);
    a.dimension_ = 2;
    a.matrix_ = {std::sin(t), std::cos(t), -std::cos(t) / g[1], std::sin(t) / g[1]};
  } else if (g.size() == 5) {
    check_positive(g[3], "anis ratio s (minor 1)");
    check_positive(g[4], "anis ratio t (minor 2)");
    // GSLIB's rotation (Deutsch and Journel 1998, sec. II.3): alpha is the azimuth turned into a
    // counter-clockwise angle from +x, beta = -dip, theta the rotation about the major axis.
    const double az = g[0];
    const double alpha = radians(az >= 0.0 && az <= 90.0 ? 90.0 - az : 450.0 - az);
    const double beta = radians(-g[1]);
    const double theta = radians(g[2]);
    const double ca = std::cos(alpha), sa = std::sin(alpha), cb = std::cos(beta), sb = std::sin(beta);
    const double ct = std::cos(theta), st = std::sin(theta);
    const double f1 = 1.0 / g[3], f2 = 1.0 / g[4];
    a.dimension_ = 3;
    a.matrix_ = {cb * ca,
                 cb * sa,
                 -sb,
                 f1 * (-ct * sa + st * sb * ca),
                 f1 * (ct * ca + st * sb * sa),
                 f1 * (st * cb),
                 f2 * (st * sa + ct * sb * ca),
                 f2 * (-st * ca + ct * sb * sa),
                 f2 * (ct * cb)};
  } else {
    throw ArgumentError("anisotropy: anis() has " + std::to_string(g.size()) +
                        " numbers; expected 2 (2-D: angle, ratio) or 5 (3-D: p, q, r, s, t), as gstat's anis");
  }
  a.parameters_ = std::move(g);
  return a;
}

Anisotropy Anisotropy::parse(std::string_view text) {
  const std::string context(text);
  text = trim(text);
  const auto open = text.find('(');
  if (open == std::string_view::npos || text.empty() || text.back() != ')')
    throw ArgumentError("anisotropy: '" + context + "' is not of the form ard(s1,...,sD) or anis(angle,ratio)");
  const std::string_view name = trim(text.substr(0, open));
  std::string_view args = text.substr(open + 1, text.size() - open - 2);
  std::vector<double> v;
  while (true) {
    const auto comma = args.find(',');
    const std::string_view item = trim(args.substr(0, comma));
    double x = 0.0;
    const char* first = item.data();
    const char* last = item.data() + item.size();
    if (first != last && *first == '+') ++first;
    const auto res = std::from_chars(first, last, x);
    if (first == last || res.ec != std::errc() || res.ptr != last || !std::isfinite(x))
      throw ArgumentError("anisotropy: '" + std::string(item) + "' in '" + context + "' is not a finite number");
    v.push_back(x);
    if (comma == std::string_view::npos) break;
    args = args.substr(comma + 1);
  }
  if (name == "ard") return ard(std::move(v));
  if (name == "anis") return rotated(std::move(v));
  throw ArgumentError("anisotropy: unknown '" + std::string(name) + "' in '" + context + "'; known: ard, anis");
}

void Anisotropy::apply(const double* in, double* out, int dimension) const {
  if (type_ == Type::None) {
    for (int k = 0; k < dimension; ++k) out[k] = in[k];
    return;
  }
  if (type_ == Type::Ard) {
    for (int k = 0; k < dimension; ++k) out[k] = in[k] * matrix_[static_cast<std::size_t>(k)];
    return;
  }
  for (int r = 0; r < dimension; ++r) {
    double s = 0.0;
    for (int c = 0; c < dimension; ++c) s += matrix_[static_cast<std::size_t>(r * dimension + c)] * in[c];
    out[r] = s;
  }
}

std::string Anisotropy::to_string() const {
  if (type_ == Type::None) return {};
  std::string s = type_ == Type::Ard ? "ard(" : "anis(";
  for (std::size_t i = 0; i < parameters_.size(); ++i) {
    if (i) s += ',';
    s += format_number(parameters_[i]);
  }
  return s + ")";
}

}  // namespace errfield
