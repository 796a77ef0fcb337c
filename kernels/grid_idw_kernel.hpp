#pragma once
// Hot loop of errfield::GridIdw (include/errfield/grid_idw.hpp): inverse-distance weighting over
// the 8 vertices of the regular-grid cell that holds each target (SPEC eqs. 19-21). Plain
// pointer signatures, no allocation, no exceptions, no checks beyond the per-target geometry;
// the caller validates its inputs before calling. OpenMP over targets; each target is computed
// independently with the same operations, so results are identical for any thread count.
//
// `grid_idw_reference` is the naive version the kernel is tested against: it finds the cell by
// scanning the nodes of each axis and uses std::pow for every weight.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace errfield::kernels {

/// Geometry of a regular grid, flattened. count[a] >= 2 nodes per axis; step[a] > 0;
/// inv_step[a] = 1 / step[a]. Node (i, j, k) is node_values[(i + nx (j + ny k)) * C + c].
struct GridIdwGeometry {
  double origin[3];
  double step[3];
  double inv_step[3];
  int count[3];
};

struct GridIdwParams {
  double power = 1.0;                ///< p >= 0: weight 1 / d^p
  double vertex_tolerance_sq = 0.0;  ///< squared distance (unit^2) within which a target takes a vertex's value
  double boundary_tolerance = 0.0;   ///< in cells: how far outside the box a target still counts as inside
  bool clamp = false;                ///< outside targets use the nearest cell instead of NaN
  int threads = 0;                   ///< OpenMP threads; 0 = OpenMP's default
};

/// Per-target outcome.
enum GridIdwKernelStatus : std::uint8_t {
  kGridInside = 0,   ///< interpolated in its cell
  kGridClamped = 1,  ///< outside the grid, interpolated from the nearest cell (clamp = true)
  kGridOutside = 2,  ///< outside (or a non-finite coordinate); output is NaN
};

namespace detail {

enum PowerMode { kPowerGeneral = 0, kPowerOne = 1, kPowerTwo = 2 };

template <int Mode>
inline double idw_weight(double d2, double power) {
  if constexpr (Mode == kPowerOne) {
    return 1.0 / std::sqrt(d2);
  } else if constexpr (Mode == kPowerTwo) {
    return 1.0 / d2;
  } else {
    return std::pow(d2, -0.5 * power);
  }
}

template <int C, int Mode>
inline std::uint8_t grid_idw_one(const GridIdwGeometry& g, const GridIdwParams& p, const double* nodes,
                                 const double pos[3], double* out) {
  std::uint8_t status = kGridInside;
  bool finite = true;
  int cell[3];
  double dd[3][2];  // squared offsets to the lower and upper vertex plane, per axis
  for (int a = 0; a < 3; ++a) {
    double t = (pos[a] - g.origin[a]) * g.inv_step[a];
    const double last = static_cast<double>(g.count[a] - 1);
    if (!(t >= -p.boundary_tolerance && t <= last + p.boundary_tolerance)) status = kGridClamped;
    if (!std::isfinite(t)) finite = false;
    t = t < 0.0 ? 0.0 : (t > last - 1.0 ? last - 1.0 : t);
    const int c = finite ? static_cast<int>(t) : 0;
    cell[a] = c;
    const double d0 = pos[a] - (g.origin[a] + c * g.step[a]);
    const double d1 = d0 - g.step[a];
    dd[a][0] = d0 * d0;
    dd[a][1] = d1 * d1;
  }
  if (!finite || (status != kGridInside && !p.clamp)) {
    for (int c = 0; c < C; ++c) out[c] = std::numeric_limits<double>::quiet_NaN();
    return kGridOutside;
  }
  const std::ptrdiff_t nx = g.count[0];
  const std::ptrdiff_t nxy = nx * g.count[1];
  const std::ptrdiff_t base = cell[0] + nx * cell[1] + nxy * cell[2];
  // Nearest vertex: the nearer plane on each axis.
  const int near_x = dd[0][1] < dd[0][0], near_y = dd[1][1] < dd[1][0], near_z = dd[2][1] < dd[2][0];
  if (dd[0][near_x] + dd[1][near_y] + dd[2][near_z] <= p.vertex_tolerance_sq) {
    const std::ptrdiff_t node = base + near_x + near_y * nx + near_z * nxy;
    for (int c = 0; c < C; ++c) out[c] = nodes[node * C + c];
    return status;
  }
#if defined(__SSE2__)
  if constexpr (Mode == kPowerOne || Mode == kPowerTwo) {
    // Vertices come in pairs along x (same y, z): squared distances (dx0^2, dx1^2) + (dy^2 + dz^2).
    const __m128d dx = _mm_set_pd(dd[0][1], dd[0][0]);
    const __m128d one = _mm_set1_pd(1.0);
    __m128d wsum = _mm_setzero_pd();
    __m128d acc[C];
    for (int c = 0; c < C; ++c) acc[c] = _mm_setzero_pd();
    for (int iz = 0; iz < 2; ++iz)
      for (int iy = 0; iy < 2; ++iy) {
        const __m128d d2 = _mm_add_pd(dx, _mm_set1_pd(dd[1][iy] + dd[2][iz]));
        const __m128d w = _mm_div_pd(one, Mode == kPowerOne ? _mm_sqrt_pd(d2) : d2);
        wsum = _mm_add_pd(wsum, w);
        const double* v0 = nodes + (base + iy * nx + iz * nxy) * C;
        if constexpr (C == 1) {
          acc[0] = _mm_add_pd(acc[0], _mm_mul_pd(w, _mm_loadu_pd(v0)));
        } else {
          for (int c = 0; c < C; ++c) acc[c] = _mm_add_pd(acc[c], _mm_mul_pd(w, _mm_set_pd(v0[C + c], v0[c])));
        }
      }
    const double ws = _mm_cvtsd_f64(wsum) + _mm_cvtsd_f64(_mm_unpackhi_pd(wsum, wsum));
    for (int c = 0; c < C; ++c) out[c] = (_mm_cvtsd_f64(acc[c]) + _mm_cvtsd_f64(_mm_unpackhi_pd(acc[c], acc[c]))) / ws;
    return status;
  }
#endif
  double acc[C];
  for (int c = 0; c < C; ++c) acc[c] = 0.0;
  double wsum = 0.0;
  // A general power weighs relative to the nearest vertex, (d_min / d)^p in (0, 1]: the same
  // ratios as 1 / d^p, without underflow to 0 / 0 for a large power (p = 1e6 gave empty
  // predictions) or overflow near a vertex.
  const double d2_near = dd[0][near_x] + dd[1][near_y] + dd[2][near_z];
  for (int v = 0; v < 8; ++v) {
    const int ix = v & 1, iy = (v >> 1) & 1, iz = v >> 2;
    const double d2 = dd[0][ix] + dd[1][iy] + dd[2][iz];
    const double w = Mode == kPowerGeneral ? std::pow(d2_near / d2, 0.5 * p.power) : idw_weight<Mode>(d2, p.power);
    wsum += w;
    const double* value = nodes + (base + ix + iy * nx + iz * nxy) * C;
    for (int c = 0; c < C; ++c) acc[c] += w * value[c];
  }
  for (int c = 0; c < C; ++c) out[c] = acc[c] / wsum;
  return status;
}

template <int C, int Mode>
void grid_idw_loop(const GridIdwGeometry& g, const GridIdwParams& p, const double* nodes, const double* targets,
                   std::ptrdiff_t target_stride, std::ptrdiff_t coord_stride, std::ptrdiff_t n, double* out,
                   std::uint8_t* status) {
  auto body = [&](std::ptrdiff_t t) {
    const double* q = targets + t * target_stride;
    const double pos[3] = {q[0], q[coord_stride], q[2 * coord_stride]};
    const std::uint8_t s = grid_idw_one<C, Mode>(g, p, nodes, pos, out + t * C);
    if (status) status[t] = s;
  };
  // Batches below ~a few microseconds of work run serially (a parallel region costs more).
  const bool parallel = n >= 2048;
  if (p.threads > 0) {
#pragma omp parallel for schedule(static) num_threads(p.threads) if (parallel)
    for (std::ptrdiff_t t = 0; t < n; ++t) body(t);
  } else {
#pragma omp parallel for schedule(static) if (parallel)
    for (std::ptrdiff_t t = 0; t < n; ++t) body(t);
  }
}

}  // namespace detail

/// IDW over the 8 vertices of each target's cell.
///  - nodes: node_count * C values (component c of node n at nodes[n * C + c]);
///  - targets: coordinate a of target t at targets[t * target_stride + a * coord_stride]
///    (row-major n x 3: strides 3, 1; column-major n x 3: strides 1, n);
///  - out: n * C values; status: n entries, or nullptr.
/// A target on an interior cell face belongs to the cell above it; on the upper boundary, to the
/// last cell. Preconditions: geometry valid (see GridIdwGeometry), power >= 0, n >= 0.
template <int C>
void grid_idw(const GridIdwGeometry& g, const GridIdwParams& p, const double* nodes, const double* targets,
              std::ptrdiff_t target_stride, std::ptrdiff_t coord_stride, std::ptrdiff_t n, double* out,
              std::uint8_t* status) {
  if (p.power == 1.0)
    detail::grid_idw_loop<C, detail::kPowerOne>(g, p, nodes, targets, target_stride, coord_stride, n, out, status);
  else if (p.power == 2.0)
    detail::grid_idw_loop<C, detail::kPowerTwo>(g, p, nodes, targets, target_stride, coord_stride, n, out, status);
  else
    detail::grid_idw_loop<C, detail::kPowerGeneral>(g, p, nodes, targets, target_stride, coord_stride, n, out, status);
}

/// One target, no OpenMP (for single-point queries): pos = (x, y, z), out = C values.
template <int C>
inline std::uint8_t grid_idw_single(const GridIdwGeometry& g, const GridIdwParams& p, const double* nodes,
                                    const double pos[3], double* out) {
  if (p.power == 1.0) return detail::grid_idw_one<C, detail::kPowerOne>(g, p, nodes, pos, out);
  if (p.power == 2.0) return detail::grid_idw_one<C, detail::kPowerTwo>(g, p, nodes, pos, out);
  return detail::grid_idw_one<C, detail::kPowerGeneral>(g, p, nodes, pos, out);
}

/// Naive reference of grid_idw with the same contract (single-threaded, `threads` ignored).
template <int C>
void grid_idw_reference(const GridIdwGeometry& g, const GridIdwParams& p, const double* nodes, const double* targets,
                        std::ptrdiff_t target_stride, std::ptrdiff_t coord_stride, std::ptrdiff_t n, double* out,
                        std::uint8_t* status) {
  for (std::ptrdiff_t t = 0; t < n; ++t) {
    double pos[3];
    for (int a = 0; a < 3; ++a) pos[a] = targets[t * target_stride + a * coord_stride];
    double* o = out + t * C;
    bool inside = true, finite = true;
    int cell[3];
    for (int a = 0; a < 3; ++a) {
      const double lo = g.origin[a];
      const double hi = g.origin[a] + (g.count[a] - 1) * g.step[a];
      const double tol = p.boundary_tolerance * g.step[a];
      if (!std::isfinite(pos[a])) finite = false;
      if (!(pos[a] >= lo - tol && pos[a] <= hi + tol)) inside = false;
      // The cell is the last one whose lower node is at or below the target, among 0..count-2.
      cell[a] = 0;
      for (int i = 0; i <= g.count[a] - 2; ++i)
        if (pos[a] >= g.origin[a] + i * g.step[a]) cell[a] = i;
    }
    if (!finite || (!inside && !p.clamp)) {
      for (int c = 0; c < C; ++c) o[c] = std::numeric_limits<double>::quiet_NaN();
      if (status) status[t] = kGridOutside;
      continue;
    }
    if (status) status[t] = inside ? kGridInside : kGridClamped;
    double dist[8];
    std::ptrdiff_t node[8];
    int v = 0;
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i, ++v) {
          const int ni = cell[0] + i, nj = cell[1] + j, nk = cell[2] + k;
          const double vx = g.origin[0] + ni * g.step[0];
          const double vy = g.origin[1] + nj * g.step[1];
          const double vz = g.origin[2] + nk * g.step[2];
          dist[v] = std::sqrt((pos[0] - vx) * (pos[0] - vx) + (pos[1] - vy) * (pos[1] - vy) +
                              (pos[2] - vz) * (pos[2] - vz));
          node[v] = ni + static_cast<std::ptrdiff_t>(g.count[0]) * (nj + static_cast<std::ptrdiff_t>(g.count[1]) * nk);
        }
    int nearest = 0;
    for (int u = 1; u < 8; ++u)
      if (dist[u] < dist[nearest]) nearest = u;
    if (dist[nearest] * dist[nearest] <= p.vertex_tolerance_sq) {
      for (int c = 0; c < C; ++c) o[c] = nodes[node[nearest] * C + c];
      continue;
    }
    double wsum = 0.0;
    for (int c = 0; c < C; ++c) o[c] = 0.0;
    for (int u = 0; u < 8; ++u) {
      const double w = std::pow(dist[nearest] / dist[u], p.power);  // relative to the nearest: no underflow
      wsum += w;
      for (int c = 0; c < C; ++c) o[c] += w * nodes[node[u] * C + c];
    }
    for (int c = 0; c < C; ++c) o[c] /= wsum;
  }
}

}  // namespace errfield::kernels
