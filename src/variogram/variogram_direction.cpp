#include "errfield/variogram_direction.hpp"

#include <cmath>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {
namespace {

void check_tolerance(double tol, const char* name) {
  if (!std::isfinite(tol) || tol < 0.0 || tol > 180.0)
    throw ArgumentError(std::string("variogram direction: ") + name + " = " + format_number(tol) +
                        " degrees; expected 0 <= " + name + " <= 180");
}

void check_angle(double a, const char* name) {
  if (!std::isfinite(a))
    throw ArgumentError(std::string("variogram direction: ") + name + " = " + format_number(a) +
                        "; expected a finite angle in degrees");
}

}  // namespace

VariogramDirection VariogramDirection::gstat(double alpha_deg, double tol_hor_deg, double beta_deg,
                                             double tol_ver_deg) {
  check_angle(alpha_deg, "alpha");
  check_angle(beta_deg, "beta");
  check_tolerance(tol_hor_deg, "tol_hor");
  check_tolerance(tol_ver_deg, "tol_ver");
  VariogramDirection d;
  d.kind_ = Kind::Gstat;
  d.alpha_ = alpha_deg;
  d.beta_ = beta_deg;
  d.tol_hor_ = tol_hor_deg;
  d.tol_ver_ = tol_ver_deg;
  return d;
}

VariogramDirection VariogramDirection::along(std::vector<double> u, double tol_deg) {
  check_tolerance(tol_deg, "tol");
  if (u.empty()) throw ArgumentError("variogram direction: empty direction vector");
  double norm2 = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    if (!std::isfinite(u[k]))
      throw ArgumentError("variogram direction: u[" + std::to_string(k) + "] = " +
                          format_number(u[k]) + "; expected a finite number");
    norm2 += u[k] * u[k];
  }
  if (!(norm2 > 0.0)) throw ArgumentError("variogram direction: the direction vector is zero");
  const double norm = std::sqrt(norm2);
  for (double& x : u) x /= norm;
  VariogramDirection d;
  d.kind_ = Kind::Vector;
  d.unit_ = std::move(u);
  d.tol_ = tol_deg;
  return d;
}

VariogramDirection VariogramDirection::axis(int k, int dimension, double tol_deg) {
  if (dimension < 1 || k < 0 || k >= dimension)
    throw ArgumentError("variogram direction: axis " + std::to_string(k) + " of a " +
                        std::to_string(dimension) + "-dimensional space; expected 0 <= axis < " +
                        std::to_string(dimension));
  std::vector<double> u(static_cast<std::size_t>(dimension), 0.0);
  u[static_cast<std::size_t>(k)] = 1.0;
  return along(std::move(u), tol_deg);
}

void VariogramDirection::check_dimension(int dimension) const {
  if (kind_ == Kind::Gstat) {
    if (dimension != 2 && dimension != 3)
      throw ArgumentError("variogram direction: alpha/beta (gstat's directions) need 2 or 3 "
                          "coordinates, got " + std::to_string(dimension) +
                          "; use a direction vector (along) or a coordinate axis instead");
    if (dimension == 2 && tol_ver_ < 90.0)
      throw ArgumentError("variogram direction: tol_ver = " + format_number(tol_ver_) +
                          " (a dip test) needs 3 coordinates, got 2");
  } else if (kind_ == Kind::Vector) {
    if (static_cast<int>(unit_.size()) != dimension)
      throw ArgumentError("variogram direction: the direction vector has " +
                          std::to_string(unit_.size()) + " entries for " + std::to_string(dimension) +
                          " coordinates");
    if (dimension > 64)
      throw ArgumentError("variogram direction: " + std::to_string(dimension) +
                          " coordinates; a direction filter handles at most 64");
  }
}

std::string VariogramDirection::to_string() const {
  switch (kind_) {
    case Kind::All: return "all";
    case Kind::Gstat: {
      std::string s = "alpha=" + format_number(alpha_) + ",tol.hor=" + format_number(tol_hor_);
      if (tol_ver_ < 90.0) s += ",beta=" + format_number(beta_) + ",tol.ver=" + format_number(tol_ver_);
      return s;
    }
    case Kind::Vector: {
      std::string s = "u=(";
      for (std::size_t k = 0; k < unit_.size(); ++k) s += (k ? "," : "") + format_number(unit_[k]);
      return s + "),tol=" + format_number(tol_);
    }
  }
  return "?";
}

}  // namespace errfield
