#pragma once
/// Direction filter of the empirical variogram's pair loop: whether the separation
/// s = x_i - x_j of a pair lies within an angular tolerance of a direction (either sign, as gstat's
/// symmetric variograms). Used by bin_pair_rows, bin_pair_rows_euclidean and
/// store_pair_differences (pair_binning.hpp) and the cell list (pair_cells.hpp), which mark a
/// rejected pair's lag NaN so that it falls in no bin, and by the sorted columns (pair_columns.hpp),
/// which test each pair in range with cone_keeps_pair (the same rule and arithmetic). The angle is
/// taken in the location coordinates, whatever the metric.
///
/// Two kinds (errfield::VariogramDirection builds them and documents the conventions):
///  - gstat (2-D/3-D): horizontal test on axes 0, 1 with the direction (sin alpha, cos alpha)
///    (alpha clockwise from +y), made only when tol_hor < 90 deg and (s_x, s_y) != 0; vertical
///    test on (|s_xy|, s_z) with (cos beta, sin beta), made only when tol_ver < 90 deg and s != 0.
///  - vector (any dimension): |s . u| >= cos(tol) |s| for a unit vector u; s = 0 is accepted.
/// Both accept an angle equal to the tolerance in exact arithmetic (cosines compared with >=).
/// Plain pointers, no allocation, no exceptions.

#include <cmath>
#include <cstddef>
#include <limits>

namespace errfield::kernels {

struct DirectionCone {
  const double* coordinates = nullptr;  ///< axis-major: coordinates[a * n + i]
  std::size_t n = 0;
  int dimension = 0;
  bool gstat = false;
  // gstat kind
  bool check_hor = false;
  double hor_x = 0.0, hor_y = 1.0, cos_tol_hor = -1.0;
  bool check_ver = false;
  double ver_xy = 1.0, ver_z = 0.0, cos_tol_ver = -1.0;
  // vector kind: unit vector of `dimension` entries
  const double* axis = nullptr;
  double cos_tol = -1.0;
};

/// Whether the separation s (dimension entries) is within the cone.
inline bool direction_accepts(const DirectionCone& c, const double* s) noexcept {
  if (c.gstat) {
    const double px = s[0];
    const double py = c.dimension > 1 ? s[1] : 0.0;
    const double pz = c.dimension > 2 ? s[2] : 0.0;
    const double xy2 = px * px + py * py;
    if (c.check_hor && xy2 != 0.0) {
      const double cosine = (px * c.hor_x + py * c.hor_y) / std::sqrt(xy2);
      if (std::fabs(cosine) < c.cos_tol_hor) return false;
    }
    if (c.check_ver && (xy2 != 0.0 || pz != 0.0)) {
      const double cosine = (std::sqrt(xy2) * c.ver_xy + pz * c.ver_z) / std::sqrt(xy2 + pz * pz);
      if (std::fabs(cosine) < c.cos_tol_ver) return false;
    }
    return true;
  }
  double dot = 0.0, norm2 = 0.0;
  for (int a = 0; a < c.dimension; ++a) {
    dot += s[a] * c.axis[a];
    norm2 += s[a] * s[a];
  }
  if (norm2 == 0.0) return true;
  return std::fabs(dot) >= c.cos_tol * std::sqrt(norm2);
}

/// Whether the cone can reject any pair: false for a tolerance of 90 degrees or more (on every
/// test it has), whose cone is the whole space, so that the caller can take the omnidirectional
/// path with the same pairs.
inline bool cone_selects(const DirectionCone& c) noexcept {
  if (c.gstat)
    return (c.check_hor && c.cos_tol_hor > 0.0) || (c.check_ver && c.cos_tol_ver > 0.0 && c.dimension > 2);
  return c.cos_tol > 0.0;
}

/// Whether the cone keeps a pair and its reverse alike (mask_directions gives s and -s the same
/// answer): true but for gstat's dip test with a nonzero dip, which looks at (|s_xy|, s_z) and
/// so at the sign of s_z, i.e. at which point of the pair is i.
inline bool cone_is_symmetric(const DirectionCone& c) noexcept {
  return !(c.gstat && c.check_ver && c.cos_tol_ver > 0.0 && c.dimension > 2 && c.ver_z != 0.0);
}

/// mask_directions' rule for one pair, with the same arithmetic (so the same answer, bit for bit):
/// d0, d1, d2 are the separation's first three coordinates (unused ones 0), `dimension` <= 3.
/// For a symmetric cone (cone_is_symmetric) the sign of the separation does not matter.
inline bool cone_keeps_pair(const DirectionCone& c, double d0, double d1, double d2) noexcept {
  if (c.gstat) {
    const double dot = d0 * c.hor_x + d1 * c.hor_y;
    const double norm2 = d0 * d0 + d1 * d1;
    if (c.check_hor && c.cos_tol_hor > 0.0) {
      const double k = c.cos_tol_hor * c.cos_tol_hor;
      if (!(dot * dot >= k * norm2)) return false;
    }
    if (c.check_ver && c.cos_tol_ver > 0.0 && c.dimension > 2) {
      const double k = c.cos_tol_ver * c.cos_tol_ver;
      const double v = std::sqrt(norm2) * c.ver_xy + d2 * c.ver_z;
      if (!(v * v >= k * (norm2 + d2 * d2))) return false;
    }
    return true;
  }
  if (!(c.cos_tol > 0.0)) return true;
  const double d[3] = {d0, d1, d2};
  double dot = 0.0, norm2 = 0.0;
  for (int a = 0; a < c.dimension; ++a) {
    dot += d[a] * c.axis[a];
    norm2 += d[a] * d[a];
  }
  const double k = c.cos_tol * c.cos_tol;
  return dot * dot >= k * norm2;
}

/// h[t] = NaN for the pairs (i, j0 + t), t < m <= 256, outside the cone (at most 64 axes). The
/// same rule as direction_accepts, written on squares so that the loops over t have no branch and
/// no square root (they vectorize): for cos T > 0, |d| >= cos T |s| <=> d^2 >= cos^2 T |s|^2; a
/// zero separation gives 0 >= 0 (accepted, as above). Rounding can differ from direction_accepts
/// only for pairs within a few ulp of the boundary.
inline void mask_directions(const DirectionCone& c, std::size_t i, std::size_t j0, std::size_t m,
                            double* h) noexcept {
  constexpr std::size_t kBlock = 256;
  double dot[kBlock], norm2[kBlock];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = c.n;
  for (std::size_t b = 0; b < m; b += kBlock) {
    const std::size_t len = m - b < kBlock ? m - b : kBlock;
    const std::size_t j = j0 + b;
    double* hb = h + b;
    if (c.gstat) {
      const double* x = c.coordinates;
      const double* y = c.coordinates + n;
      const double xi = x[i], yi = y[i];
      for (std::size_t t = 0; t < len; ++t) {
        const double dx = xi - x[j + t], dy = yi - y[j + t];
        dot[t] = dx * c.hor_x + dy * c.hor_y;
        norm2[t] = dx * dx + dy * dy;
      }
      if (c.check_hor && c.cos_tol_hor > 0.0) {
        const double k = c.cos_tol_hor * c.cos_tol_hor;
        for (std::size_t t = 0; t < len; ++t) hb[t] = dot[t] * dot[t] >= k * norm2[t] ? hb[t] : nan;
      }
      if (c.check_ver && c.cos_tol_ver > 0.0 && c.dimension > 2) {
        const double* z = c.coordinates + 2 * n;
        const double zi = z[i];
        const double k = c.cos_tol_ver * c.cos_tol_ver;
        for (std::size_t t = 0; t < len; ++t) {
          const double dz = zi - z[j + t];
          const double v = std::sqrt(norm2[t]) * c.ver_xy + dz * c.ver_z;
          hb[t] = v * v >= k * (norm2[t] + dz * dz) ? hb[t] : nan;
        }
      }
      continue;
    }
    if (!(c.cos_tol > 0.0)) continue;  // a tolerance >= 90 degrees keeps every pair
    for (std::size_t t = 0; t < len; ++t) dot[t] = norm2[t] = 0.0;
    for (int a = 0; a < c.dimension; ++a) {
      const double* x = c.coordinates + static_cast<std::size_t>(a) * n;
      const double xa = x[i], ua = c.axis[a];
      for (std::size_t t = 0; t < len; ++t) {
        const double d = xa - x[j + t];
        dot[t] += d * ua;
        norm2[t] += d * d;
      }
    }
    const double k = c.cos_tol * c.cos_tol;
    for (std::size_t t = 0; t < len; ++t) hb[t] = dot[t] * dot[t] >= k * norm2[t] ? hb[t] : nan;
  }
}

}  // namespace errfield::kernels
