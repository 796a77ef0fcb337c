#include "kriging/vecchia_neighbours.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <queue>
#include <random>
#include <utility>

#include "kriging/kd_tree.hpp"

namespace errfield::detail {
namespace {

// Max-min ordering with lazy updates: when sample p is placed at distance l from those placed
// before (the largest such distance left), only samples nearer than l to p can get nearer to the
// placed set, so one radius search per placement keeps every distance current; the heap holds
// stale entries that are skipped when popped. Ties go to the smaller sample index.
std::vector<Eigen::Index> max_min_order(const Eigen::MatrixXd& points) {
  const auto n = static_cast<std::size_t>(points.cols());
  std::vector<Eigen::Index> order;
  order.reserve(n);
  if (n == 0) return order;
  const Eigen::VectorXd centroid = points.rowwise().mean();
  std::size_t first = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const double d2 = (points.col(static_cast<Eigen::Index>(i)) - centroid).squaredNorm();
    if (d2 < best) best = d2, first = i;
  }
  std::vector<double> nearest2(n);  // squared distance to the placed samples
  std::vector<char> placed(n, 0);
  using Entry = std::pair<double, std::int64_t>;  // (squared distance, -index): max-heap
  std::priority_queue<Entry> heap;
  for (std::size_t i = 0; i < n; ++i) {
    nearest2[i] = (points.col(static_cast<Eigen::Index>(i)) - points.col(static_cast<Eigen::Index>(first))).squaredNorm();
    heap.emplace(nearest2[i], -static_cast<std::int64_t>(i));
  }
  const PointTree tree(points);
  std::vector<std::pair<std::size_t, double>> found;
  auto place = [&](std::size_t p) {
    placed[p] = 1;
    order.push_back(static_cast<Eigen::Index>(p));
    const double r2 = nearest2[p];
    nearest2[p] = 0.0;
    if (!(r2 > 0.0)) return;
    found.clear();
    tree.within(points.col(static_cast<Eigen::Index>(p)).data(), r2, found);
    for (const auto& [q, d2] : found)
      if (!placed[q] && d2 < nearest2[q]) {
        nearest2[q] = d2;
        heap.emplace(d2, -static_cast<std::int64_t>(q));
      }
  };
  place(first);
  while (!heap.empty()) {
    const auto [d2, negative] = heap.top();
    heap.pop();
    const auto q = static_cast<std::size_t>(-negative);
    if (placed[q] || d2 != nearest2[q]) continue;
    place(q);
  }
  return order;
}

std::vector<Eigen::Index> random_order(std::size_t n) {
  std::vector<Eigen::Index> order(n);
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::mt19937_64 rng(20261126);  // Fisher-Yates by hand: std::shuffle differs between libraries
  for (std::size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  return order;
}

std::vector<Eigen::Index> coordinate_order(const Eigen::MatrixXd& points) {
  std::vector<Eigen::Index> order(static_cast<std::size_t>(points.cols()));
  std::iota(order.begin(), order.end(), Eigen::Index{0});
  std::stable_sort(order.begin(), order.end(), [&](Eigen::Index a, Eigen::Index b) { return points(0, a) < points(0, b); });
  return order;
}

}  // namespace

std::size_t VecchiaNeighbours::largest_set() const {
  std::size_t m = 0;
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i) m = std::max(m, offsets[i + 1] - offsets[i]);
  return m;
}

VecchiaNeighbours find_vecchia_neighbours(const Eigen::MatrixXd& points, int m, VecchiaOrdering ordering) {
  const auto n = static_cast<std::size_t>(points.cols());
  const auto mm = static_cast<std::size_t>(std::max(m, 1));
  VecchiaNeighbours nb;
  nb.order = ordering == VecchiaOrdering::MaxMin   ? max_min_order(points)
             : ordering == VecchiaOrdering::Random ? random_order(n)
                                                   : coordinate_order(points);
  nb.offsets.resize(n + 1);
  for (std::size_t i = 0; i < n; ++i) nb.offsets[i + 1] = nb.offsets[i] + std::min(i, mm);
  nb.sets.resize(nb.offsets[n]);
  Eigen::MatrixXd ordered(points.rows(), static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) ordered.col(static_cast<Eigen::Index>(i)) = points.col(nb.order[i]);
  // Positions up to m: every predecessor (nearest first).
  const std::size_t head = std::min(n, mm + 1);
  for (std::size_t i = 1; i < head; ++i) {
    std::vector<std::pair<double, std::size_t>> d(i);
    for (std::size_t j = 0; j < i; ++j)
      d[j] = {(ordered.col(static_cast<Eigen::Index>(i)) - ordered.col(static_cast<Eigen::Index>(j))).squaredNorm(), j};
    std::sort(d.begin(), d.end());
    for (std::size_t j = 0; j < i; ++j) nb.sets[nb.offsets[i] + j] = nb.order[d[j].second];
  }
  // Positions [b, 2b): a kd-tree over positions [0, 2b), queried for more and more nearest points
  // until m of them precede the position (about half of the tree does).
  for (std::size_t b = head; b < n; b *= 2) {
    const std::size_t end = std::min(n, 2 * b);
    const Eigen::MatrixXd prefix = ordered.leftCols(static_cast<Eigen::Index>(end));
    const PointTree tree(prefix);
#pragma omp parallel
    {
      std::vector<std::size_t> index;
      std::vector<double> d2;
#pragma omp for schedule(dynamic, 256)
      for (std::size_t i = b; i < end; ++i) {
        std::size_t k = std::min(end, 2 * mm + 2);
        for (;;) {
          index.resize(k);
          d2.resize(k);
          const std::size_t got = tree.nearest(prefix.col(static_cast<Eigen::Index>(i)).data(), k, index.data(), d2.data());
          std::size_t kept = 0;
          for (std::size_t j = 0; j < got && kept < mm; ++j)
            if (index[j] < i) ++kept;
          if (kept == mm || k >= end) {
            std::size_t w = nb.offsets[i];
            for (std::size_t j = 0; j < got && w < nb.offsets[i + 1]; ++j)
              if (index[j] < i) nb.sets[w++] = nb.order[index[j]];
            break;
          }
          k = std::min(end, 2 * k);
        }
      }
    }
  }
  return nb;
}

double vecchia_memory_bytes(std::size_t n, int m, std::size_t columns, std::size_t parameters) {
  const double nn = static_cast<double>(n), mm = static_cast<double>(m);
  // sets and offsets; whitened columns and their derivatives; log d and its derivatives; the
  // ordering's tree, heap and copies of the points (~ 200 bytes a sample).
  return nn * (8.0 * mm + 16.0 + 8.0 * static_cast<double>(columns * (parameters + 1)) +
               8.0 * static_cast<double>(parameters + 1) + 200.0);
}

}  // namespace errfield::detail
