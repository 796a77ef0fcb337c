#pragma once
// Euclidean k-nearest and radius search over points stored as a flat array of doubles, on top of
// nanoflann's k-d tree. Used by the scattered estimators (ScatteredIdw, ...); coordinates may be
// pre-scaled per axis so that a weighted Euclidean metric becomes a plain Euclidean one.
// Immutable after construction; queries are const and safe from several threads.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include <nanoflann.hpp>

namespace errfield::detail {

class EuclideanNeighbourIndex {
 public:
  using Index = std::uint32_t;

  /// points: n * dim coordinates (point i at points[i * dim .. i * dim + dim - 1]).
  /// Precondition: n < 2^32, dim >= 1, all finite.
  EuclideanNeighbourIndex(std::vector<double> points, std::size_t dim)
      : data_(std::make_unique<Data>(std::move(points), dim)) {}

  std::size_t size() const noexcept { return data_->source.n; }
  std::size_t dimension() const noexcept { return data_->source.dim; }

  /// The min(k, size()) nearest points to q (dim coordinates), nearest first: indices and squared
  /// distances. idx and d2 must hold k entries. Returns how many were found.
  std::size_t knn(const double* q, std::size_t k, Index* idx, double* d2) const {
    nanoflann::KNNResultSet<double, Index, std::size_t> result(k);
    result.init(idx, d2);
    data_->tree.findNeighbors(result, q, nanoflann::SearchParams());
    return result.size();
  }

  /// All points with squared distance <= r2 (unsorted), appended to `out` after clearing it.
  void within(const double* q, double r2, std::vector<std::pair<Index, double>>& out) const {
    out.clear();
    Collector c{r2, &out};
    data_->tree.findNeighbors(c, q, nanoflann::SearchParams(32, 0.0f, false));
  }

 private:
  struct Source {
    Source(std::vector<double> c, std::size_t d) : coords(std::move(c)), n(coords.size() / d), dim(d) {}
    std::vector<double> coords;
    std::size_t n;
    std::size_t dim;
    std::size_t kdtree_get_point_count() const { return n; }
    double kdtree_get_pt(Index i, std::size_t d) const { return coords[static_cast<std::size_t>(i) * dim + d]; }
    template <class BBox>
    bool kdtree_get_bbox(BBox&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Source, double, Index>,
                                                   Source, -1, Index>;
  // Inclusive radius (nanoflann's own RadiusResultSet is strict, and its leaf test is `<`).
  struct Collector {
    double r2;
    std::vector<std::pair<Index, double>>* out;
    std::size_t size() const { return out->size(); }
    bool full() const { return true; }
    bool addPoint(double d2, Index i) {
      if (d2 <= r2) out->emplace_back(i, d2);
      return true;
    }
    double worstDist() const { return std::nextafter(r2, std::numeric_limits<double>::infinity()); }
  };
  struct Data {
    Data(std::vector<double> points, std::size_t dim)
        : source(std::move(points), dim),
          tree(static_cast<int>(dim), source, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
    Source source;
    Tree tree;
  };
  std::shared_ptr<const Data> data_;
};

}  // namespace errfield::detail
