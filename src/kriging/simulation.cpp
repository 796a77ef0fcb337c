// Conditional Gaussian simulation by conditioning an unconditional realisation by kriging
// (errfield/conditional_simulation.hpp; the mathematics: docs/kriging.md, "Conditional simulation").

#include "errfield/conditional_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <random>

#include <Eigen/Cholesky>

#include "covariance_kernel.hpp"
#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "kriging/kd_tree.hpp"

namespace errfield {

std::string_view unconditional_method_name(UnconditionalMethod method) {
  switch (method) {
    case UnconditionalMethod::Auto: return "auto";
    case UnconditionalMethod::Cholesky: return "cholesky";
    case UnconditionalMethod::Sequential: return "sequential";
  }
  return "auto";
}

UnconditionalMethod unconditional_method_from_name(std::string_view name) {
  if (name == "auto") return UnconditionalMethod::Auto;
  if (name == "cholesky") return UnconditionalMethod::Cholesky;
  if (name == "sequential") return UnconditionalMethod::Sequential;
  throw ArgumentError("simulation method '" + std::string(name) + "': expected auto, cholesky or sequential");
}

void SimulationOptions::validate() const {
  if (draws < 1) throw ArgumentError("simulation options: draws = 0; expected at least 1");
  if (neighbours < 1) throw ArgumentError("simulation options: neighbours = 0; expected at least 1");
  if (draws_per_path < 1) throw ArgumentError("simulation options: draws_per_path = 0; expected at least 1");
  if (cholesky_limit > 20000)
    throw ArgumentError("simulation options: cholesky_limit = " + std::to_string(cholesky_limit) +
                        "; expected at most 20000 (the factor of 20,000 locations is 3.2 GB)");
}

namespace detail {

namespace {

// Distinct places (exactly equal columns are one place, so that they get one value): the index of
// each column's place, and the places in order of first appearance.
struct DistinctPlaces {
  Eigen::MatrixXd points;            // D x U
  std::vector<Eigen::Index> of;      // M entries in [0, U)
};

DistinctPlaces distinct_places(const Eigen::MatrixXd& places) {
  const Eigen::Index m = places.cols();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(m));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) {
    for (Eigen::Index k = 0; k < places.rows(); ++k)
      if (places(k, a) != places(k, b)) return places(k, a) < places(k, b);
    return a < b;
  });
  // representative of each column: the first column (lowest index) with equal coordinates
  std::vector<Eigen::Index> first(static_cast<std::size_t>(m));
  for (std::size_t k = 0; k < order.size(); ++k)
    first[static_cast<std::size_t>(order[k])] =
        k > 0 && places.col(order[k]) == places.col(order[k - 1]) ? first[static_cast<std::size_t>(order[k - 1])] : order[k];
  DistinctPlaces d;
  d.of.assign(static_cast<std::size_t>(m), -1);
  std::vector<Eigen::Index> columns;
  for (Eigen::Index j = 0; j < m; ++j) {
    const Eigen::Index f = first[static_cast<std::size_t>(j)];
    if (f == j) {
      d.of[static_cast<std::size_t>(j)] = static_cast<Eigen::Index>(columns.size());
      columns.push_back(j);
    } else {
      d.of[static_cast<std::size_t>(j)] = d.of[static_cast<std::size_t>(f)];
    }
  }
  d.points.resize(places.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t u = 0; u < columns.size(); ++u) d.points.col(static_cast<Eigen::Index>(u)) = places.col(columns[u]);
  return d;
}

constexpr std::size_t kScanOnly = 64;  // below this many earlier places a scan beats a tree

std::mt19937_64 generator(std::uint64_t seed, std::uint64_t stream) {
  std::seed_seq s{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                  static_cast<std::uint32_t>(stream), static_cast<std::uint32_t>(stream >> 32)};
  return std::mt19937_64(s);
}

// Exact: the covariance of the distinct places factored once (pivoted LDL', which also takes
// the positive semi-definite matrices of nugget-free smooth models), x = P' L D^1/2 e.
Eigen::MatrixXd cholesky_draws(const Eigen::MatrixXd& points, const kernels::CovarianceKernel& kernel, double zero_lag,
                               std::size_t columns, std::uint64_t seed) {
  const Eigen::Index u = points.cols();
  const int d = static_cast<int>(points.rows());
  Eigen::MatrixXd k(u, u);
  kernels::covariance_block(kernel, points.data(), static_cast<std::size_t>(u), points.data(), static_cast<std::size_t>(u),
                            d, zero_lag, k.data(), static_cast<std::size_t>(u));
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(k);
  if (ldlt.info() != Eigen::Success) throw Error("simulation: the covariance of the locations could not be factored");
  const Eigen::VectorXd root_d = ldlt.vectorD().cwiseMax(0.0).cwiseSqrt();
  std::mt19937_64 rng = generator(seed, 0x43484f4cULL);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd e(u, static_cast<Eigen::Index>(columns));
  for (Eigen::Index c = 0; c < e.cols(); ++c)
    for (Eigen::Index i = 0; i < u; ++i) e(i, c) = normal(rng);
  Eigen::MatrixXd y = ldlt.matrixL() * (root_d.asDiagonal() * e);
  return ldlt.transpositionsP().transpose() * y;
}

// One random path's conditioning, a segment of the path at a time: for the place at each position,
// the earlier places it is conditioned on and their simple-kriging weights (at most `neighbours`
// each, in one flat buffer with that stride), and the standard deviation of its draw. The buffers
// are reused from segment to segment: the whole path's weights at once were 10 MB of fresh memory
// for 10,300 places (each new page is a fault the kernel clears: 8 % of the run, 2026-11-29).
struct PathSegment {
  std::size_t begin = 0, end = 0;      // path positions [begin, end)
  std::vector<Eigen::Index> neighbour;  // (end - begin) x stride
  std::vector<double> weight;           // (end - begin) x stride
  std::vector<std::size_t> count;       // neighbours used at each position
  std::vector<double> sd;
};

// The conditioning of the places at path positions [begin, end) on their nearest earlier places.
// The earlier places are found exactly, in two parts: a kd-tree over the places before a checkpoint
// (rebuilt at checkpoints growing by a factor 1.25; the segments run from one checkpoint to the next)
// and a scan of the few placed since. Every position of a segment sees the same tree, so they are
// computed in parallel; each step depends only on the path, so the result does not depend on the
// thread count.
void condition_segment(const Eigen::MatrixXd& points, const std::vector<Eigen::Index>& path,
                       const kernels::CovarianceKernel& kernel, double zero_lag, std::size_t neighbours,
                       PathSegment& segment) {
  const int d = static_cast<int>(points.rows());
  const std::size_t begin = segment.begin, end = segment.end;
  const std::size_t tree_size = begin < kScanOnly ? 0 : begin;
  const std::size_t length = end - begin;
  segment.neighbour.resize(length * neighbours);
  segment.weight.resize(length * neighbours);
  segment.count.resize(length);
  segment.sd.resize(length);
  Eigen::MatrixXd tree_points(points.rows(), static_cast<Eigen::Index>(tree_size));
  for (std::size_t j = 0; j < tree_size; ++j) tree_points.col(static_cast<Eigen::Index>(j)) = points.col(path[j]);
  std::unique_ptr<PointTree> tree;
  if (tree_size > 0) tree = std::make_unique<PointTree>(tree_points);
#pragma omp parallel
  {
    // One workspace per thread: no allocation per step once the sizes settle.
    std::vector<std::size_t> index(neighbours);
    std::vector<double> d2(neighbours);
    std::vector<std::pair<double, std::size_t>> candidates;  // (squared distance, path position)
    Eigen::MatrixXd a, factor;
    Eigen::VectorXd b, w;
    std::vector<double> coordinates, lags, origin(static_cast<std::size_t>(d));
#pragma omp for schedule(dynamic, 16)
    for (std::size_t t = begin; t < end; ++t) {
      Eigen::Index* chosen = segment.neighbour.data() + (t - begin) * neighbours;
      const double* here = points.col(path[t]).data();
      candidates.clear();
      // A place scanned beyond the tree's k-th nearest cannot be among the k nearest (on a tie
      // the tree's, earlier on the path, comes first): only closer ones are kept for the sort.
      double worst = std::numeric_limits<double>::infinity();
      if (tree) {
        const std::size_t found = tree->nearest(here, std::min(neighbours, tree_size), index.data(), d2.data());
        for (std::size_t j = 0; j < found; ++j) candidates.emplace_back(d2[j], index[j]);
        if (found == neighbours) worst = d2[found - 1];
      }
      // Squared distances, as the tree's (no square root for the up to a fifth of the path scanned).
      for (std::size_t j = tree_size; j < t; ++j) {
        const double* there = points.col(path[j]).data();
        double h2 = 0.0;
        for (int k = 0; k < d; ++k) h2 += (there[k] - here[k]) * (there[k] - here[k]);
        if (h2 < worst) candidates.emplace_back(h2, j);
      }
      const std::size_t n = std::min(neighbours, candidates.size());
      std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(n), candidates.end());
      segment.count[t - begin] = n;
      for (std::size_t j = 0; j < n; ++j) chosen[j] = path[candidates[j].second];
      if (n == 0) {
        segment.sd[t - begin] = std::sqrt(zero_lag);
        continue;
      }
      const auto ni = static_cast<Eigen::Index>(n);
      a.resize(ni, ni);
      b.resize(ni);
      // The covariances: lags a column at a time (the lower triangle, all either factorization
      // reads), from the neighbours' coordinates laid out coordinate by coordinate, then the
      // kernel over the column (CovarianceKernel::at_lags). The same values, bit for bit, as
      // kernel(column_distance(...)) pair by pair.
      coordinates.resize(n * static_cast<std::size_t>(d));
      for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < d; ++k) coordinates[static_cast<std::size_t>(k) * n + i] = points(k, chosen[i]);
      lags.resize(n);
      auto lags_from = [&](const double* from, std::size_t first) {  // |neighbour i - from|, i >= first
        std::fill(lags.begin() + static_cast<std::ptrdiff_t>(first), lags.end(), 0.0);
        for (int k = 0; k < d; ++k) {
          const double* x = coordinates.data() + static_cast<std::size_t>(k) * n;
          const double f = from[k];
          for (std::size_t i = first; i < n; ++i) lags[i] += (x[i] - f) * (x[i] - f);
        }
        // Eigen's packet square root: the correctly rounded one, two lags per instruction (std::sqrt
        // in a loop stays scalar for errno's sake).
        auto tail = Eigen::Map<Eigen::ArrayXd>(lags.data() + first, static_cast<Eigen::Index>(n - first));
        tail = tail.sqrt();
      };
      lags_from(here, 0);
      kernel.at_lags(lags.data(), n, zero_lag, b.data());
      for (std::size_t j = 0; j < n; ++j) {
        for (int k = 0; k < d; ++k) origin[static_cast<std::size_t>(k)] = coordinates[static_cast<std::size_t>(k) * n + j];
        lags_from(origin.data(), j);
        kernel.at_lags(lags.data() + j, n - j, zero_lag, &a(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)));
      }
      // Cholesky (cheaper than the pivoted LDL', which it replaced), unblocked: Eigen's LLT
      // blocks systems of 32 and more, which at 60 x 60 costs 1.5x the plain column algorithm
      // (21 against 15 us measured, 2026-11-29). The pivoted LDL' when the matrix is only
      // semi-definite (coincident-looking neighbours of a smooth model without nugget).
      factor = a;
      if (Eigen::internal::llt_inplace<double, Eigen::Lower>::unblocked(factor) == -1) {
        w = b;
        factor.triangularView<Eigen::Lower>().solveInPlace(w);
        factor.triangularView<Eigen::Lower>().transpose().solveInPlace(w);
      } else {
        const Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
        w = ldlt.solve(b);
      }
      std::copy(w.data(), w.data() + w.size(), segment.weight.data() + (t - begin) * neighbours);
      segment.sd[t - begin] = std::sqrt(std::max(zero_lag - b.dot(w), 0.0));
    }
  }
}

// Sequential draws, place-major: the result's column j holds the `columns` draws at place j (each
// neighbour's contribution to a place is then one contiguous update, and the conditioning needs
// no transpose). Per random path: a segment's conditioning (in parallel), then the segment's
// draws place by place, in path order (the same sums in the same order as one pass over the path).
Eigen::MatrixXd sequential_draws_by_place(const Eigen::MatrixXd& points, const kernels::CovarianceKernel& kernel,
                                          double zero_lag, std::size_t columns, const SimulationOptions& options) {
  const Eigen::Index u = points.cols();
  const std::size_t m = static_cast<std::size_t>(u);
  Eigen::MatrixXd y(static_cast<Eigen::Index>(columns), u);
  std::normal_distribution<double> normal;
  PathSegment segment;
  for (std::size_t first = 0, group = 0; first < columns; first += options.draws_per_path, ++group) {
    const std::size_t width = std::min(options.draws_per_path, columns - first);
    std::mt19937_64 rng = generator(options.seed, 0x53475300ULL + group);
    std::vector<Eigen::Index> path(m);
    std::iota(path.begin(), path.end(), Eigen::Index{0});
    for (std::size_t i = path.size(); i > 1; --i)  // Fisher-Yates with the generator's own integers
      std::swap(path[i - 1], path[std::uniform_int_distribution<std::size_t>(0, i - 1)(rng)]);
    auto block = y.middleRows(static_cast<Eigen::Index>(first), static_cast<Eigen::Index>(width));
    Eigen::VectorXd mean(static_cast<Eigen::Index>(width));
    for (std::size_t begin = 0; begin < m;) {
      segment.begin = begin;
      segment.end = begin < kScanOnly ? std::min(kScanOnly, m) : std::min(m, std::max(begin + 1, begin + begin / 4));
      condition_segment(points, path, kernel, zero_lag, options.neighbours, segment);
      for (std::size_t t = segment.begin; t < segment.end; ++t) {
        const std::size_t row = t - segment.begin;
        const Eigen::Index* chosen = segment.neighbour.data() + row * options.neighbours;
        const double* weight = segment.weight.data() + row * options.neighbours;
        const double sd = segment.sd[row];
        mean.setZero();
        for (std::size_t j = 0; j < segment.count[row]; ++j) mean += weight[j] * block.col(chosen[j]);
        auto here = block.col(path[t]);
        for (Eigen::Index c = 0; c < here.size(); ++c) here[c] = mean[c] + sd * normal(rng);
      }
      begin = segment.end;
    }
  }
  return y;
}

// The exact or the sequential draws at the distinct places, place-major (columns x distinct places).
Eigen::MatrixXd unconditional_by_distinct_place(const DistinctPlaces& distinct, const kernels::CovarianceKernel& kernel,
                                                double zero_lag_variance, std::size_t columns,
                                                const SimulationOptions& options, std::string& method) {
  const std::size_t u = static_cast<std::size_t>(distinct.points.cols());
  const bool exact = options.method == UnconditionalMethod::Cholesky ||
                     (options.method == UnconditionalMethod::Auto && u <= options.cholesky_limit);
  if (options.method == UnconditionalMethod::Cholesky && u > 20000)
    throw ResourceError("simulation: the Cholesky method over " + std::to_string(u) +
                        " distinct locations needs more than 3.2 GB; use the sequential method");
  if (exact) {
    method = "cholesky (exact, " + std::to_string(u) + " distinct locations)";
    if (u == 0) return Eigen::MatrixXd(static_cast<Eigen::Index>(columns), 0);
    return cholesky_draws(distinct.points, kernel, zero_lag_variance, columns, options.seed).transpose();
  }
  method = "sequential (" + std::to_string(options.neighbours) + " neighbours, " +
           std::to_string(options.draws_per_path) + " draws per random path, " + std::to_string(u) +
           " distinct locations)";
  return sequential_draws_by_place(distinct.points, kernel, zero_lag_variance, columns, options);
}

// simulate_unconditional_embedded's draws, place-major: columns x M (column j: the draws at place j).
Eigen::MatrixXd unconditional_by_place(const Eigen::MatrixXd& places, const VariogramModel& model,
                                       double zero_lag_variance, std::size_t columns,
                                       const SimulationOptions& options, std::string& method) {
  options.validate();
  const kernels::CovarianceKernel kernel(model);
  const DistinctPlaces distinct = distinct_places(places);
  Eigen::MatrixXd y = unconditional_by_distinct_place(distinct, kernel, zero_lag_variance, columns, options, method);
  // Every place distinct (the usual case): y is the answer. Otherwise a gather of whole columns.
  bool identity = y.cols() == places.cols();
  for (std::size_t j = 0; j < distinct.of.size() && identity; ++j) identity = distinct.of[j] == static_cast<Eigen::Index>(j);
  if (identity) return y;
  Eigen::MatrixXd out(static_cast<Eigen::Index>(columns), places.cols());
  for (Eigen::Index j = 0; j < places.cols(); ++j) out.col(j) = y.col(distinct.of[static_cast<std::size_t>(j)]);
  return out;
}

}  // namespace

Eigen::MatrixXd embed_columns(const Eigen::MatrixXd& raw, const std::vector<double>& scales, const Anisotropy& anisotropy) {
  if (!anisotropy.isotropic() && anisotropy.dimension() != raw.rows())
    throw ArgumentError("simulation: the model's anisotropy " + anisotropy.to_string() + " is for " +
                        std::to_string(anisotropy.dimension()) + " coordinates but locations have " +
                        std::to_string(raw.rows()));
  if (!scales.empty() && static_cast<Eigen::Index>(scales.size()) != raw.rows())
    throw ArgumentError("simulation: the metric has " + std::to_string(scales.size()) + " weights but locations have " +
                        std::to_string(raw.rows()) + " coordinates");
  Eigen::MatrixXd e = raw;
  for (std::size_t k = 0; k < scales.size(); ++k) e.row(static_cast<Eigen::Index>(k)) *= scales[k];
  if (anisotropy.isotropic()) return e;
  Eigen::MatrixXd mapped(e.rows(), e.cols());
  for (Eigen::Index j = 0; j < e.cols(); ++j)
    anisotropy.apply(e.col(j).data(), mapped.col(j).data(), static_cast<int>(e.rows()));
  return mapped;
}

Eigen::MatrixXd simulate_unconditional_embedded(const Eigen::MatrixXd& places, const VariogramModel& model,
                                                double zero_lag_variance, std::size_t columns,
                                                const SimulationOptions& options, std::string& method) {
  return unconditional_by_place(places, model, zero_lag_variance, columns, options, method).transpose();
}

SimulationOutput simulate_conditional_embedded(Eigen::MatrixXd sample_embedded, Eigen::MatrixXd sample_raw,
                                               Eigen::MatrixXd values, Eigen::VectorXd measurement_variance,
                                               const Eigen::MatrixXd& target_embedded, const Eigen::MatrixXd& target_raw,
                                               const VariogramModel& model, const KrigingOptions& kriging,
                                               const SimulationOptions& options) {
  options.validate();
  const kernels::CovarianceKernel kernel(model);
  const Eigen::Index n = sample_embedded.cols(), t = target_embedded.cols(), c = values.cols();
  const auto draws = static_cast<Eigen::Index>(options.draws);
  const double bytes = 3.0 * 8.0 * static_cast<double>(n + t) * static_cast<double>(draws) * static_cast<double>(c);
  if (bytes > static_cast<double>(options.memory_budget_bytes))
    throw ResourceError("simulation: " + std::to_string(draws) + " draws at " + std::to_string(n) + " samples + " +
                        std::to_string(t) + " targets need about " + format_number(bytes / (1024.0 * 1024.0)) +
                        " MiB, over the budget of " +
                        format_number(static_cast<double>(options.memory_budget_bytes) / (1024.0 * 1024.0)) +
                        " MiB; ask for fewer draws or split the targets");

  // The unconditional field: the whole process with a micro-scale nugget (C(0) = total sill), the
  // signal alone when the nugget is measurement error.
  const bool nugget_is_noise = kriging.nugget == NuggetTreatment::MeasurementError;
  const double zero_lag = nugget_is_noise ? kernel.sill() - kernel.nugget() : kernel.sill();
  Eigen::MatrixXd places(sample_embedded.rows(), n + t);
  places << sample_embedded, target_embedded;
  SimulationOutput out;
  // Place-major (draws x places): the draws at the samples are its first n columns.
  Eigen::MatrixXd y = unconditional_by_place(places, model, zero_lag, static_cast<std::size_t>(draws * c), options,
                                             out.method);

  // The samples' observations of Y: plus each one's noise, as the data carry theirs.
  Eigen::MatrixXd extended(n, c * (1 + draws));
  extended.leftCols(c) = values;
  extended.rightCols(c * draws) = y.leftCols(n).transpose();
  {
    std::mt19937_64 rng = generator(options.seed, 0x4e4f4953ULL);
    std::normal_distribution<double> normal;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double noise = (measurement_variance.size() ? measurement_variance[i] : 0.0) +
                           (nugget_is_noise ? kernel.nugget() : 0.0);
      const double sd = std::sqrt(std::max(noise, 0.0));
      for (Eigen::Index j = c; j < extended.cols(); ++j) extended(i, j) += sd * normal(rng);
    }
  }
  // Simple kriging subtracts the known mean from every column; Y has mean 0, so it is given with
  // the mean added and taken back below.
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(c);
  if (kriging.kind == KrigingKind::Simple && !kriging.simple_mean.empty())
    for (Eigen::Index k = 0; k < c; ++k)
      shift[k] = kriging.simple_mean.size() == 1 ? kriging.simple_mean[0] : kriging.simple_mean[static_cast<std::size_t>(k)];
  for (Eigen::Index d = 0; d < draws; ++d)
    for (Eigen::Index k = 0; k < c; ++k) extended.col(c + d * c + k).array() += shift[k];

  const auto engine = make_kriging_engine(std::move(sample_embedded), std::move(sample_raw), std::move(extended),
                                          std::move(measurement_variance), model, kriging);
  KrigingOutput predicted = engine_predict(*engine, target_embedded, target_raw);
  out.kriging.status = predicted.status;
  out.kriging.message = predicted.message;
  out.kriging.failed_targets = predicted.failed_targets;
  out.kriging.variance = predicted.variance;
  if (predicted.mean.rows() != t) return out;  // not usable: no predictions at all
  out.kriging.mean = predicted.mean.leftCols(c);
  // Z* + (Y + shift) - Y*, in tiles of targets: y is read a place (a column) at a time and each
  // draw's column written down a tile, both while they are in cache.
  out.draws.assign(static_cast<std::size_t>(draws), Eigen::MatrixXd(t, c));
  constexpr Eigen::Index kTile = 256;
  for (Eigen::Index first = 0; first < t; first += kTile) {
    const Eigen::Index last = std::min(t, first + kTile);
    for (Eigen::Index d = 0; d < draws; ++d) {
      Eigen::MatrixXd& draw = out.draws[static_cast<std::size_t>(d)];
      for (Eigen::Index k = 0; k < c; ++k) {
        const Eigen::Index column = d * c + k;
        for (Eigen::Index i = first; i < last; ++i)
          draw(i, k) = predicted.mean(i, k) + (y(column, n + i) + shift[k]) - predicted.mean(i, c + column);
      }
    }
  }
  return out;
}

}  // namespace detail
}  // namespace errfield
