#pragma once
// A kd-tree over the columns of a D x N column-major matrix (points already in a Euclidean
// embedding), wrapping nanoflann 1.4. Queries are const and may run concurrently.

#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <nanoflann.hpp>

namespace errfield::detail {

class PointTree {
 public:
  /// `points` must outlive the tree and stay unchanged.
  explicit PointTree(const Eigen::MatrixXd& points)
      : cloud_{&points},
        tree_(std::make_unique<Tree>(static_cast<int>(points.rows()), cloud_,
                                     nanoflann::KDTreeSingleIndexAdaptorParams(16))) {}
  // The tree refers to cloud_, so the object must stay where it is.
  PointTree(const PointTree&) = delete;
  PointTree& operator=(const PointTree&) = delete;

  /// The k nearest points (fewer if N < k), nearest first; squared distances in d2.
  std::size_t nearest(const double* query, std::size_t k, std::size_t* index, double* d2) const {
    return tree_->knnSearch(query, k, index, d2);
  }
  /// Coordinates per point (the rows of the matrix).
  int dimension() const { return static_cast<int>(cloud_.m->rows()); }
  /// The coordinates of point i (`dimension()` doubles).
  const double* point(std::size_t i) const { return cloud_.m->col(static_cast<Eigen::Index>(i)).data(); }
  /// All points at squared distance < r2 (unsorted), as (index, squared distance).
  std::size_t within(const double* query, double r2,
                     std::vector<std::pair<std::size_t, double>>& out) const {
    return tree_->radiusSearch(query, r2, out, nanoflann::SearchParams(32, 0.0f, false));
  }

 private:
  struct Cloud {
    const Eigen::MatrixXd* m;
    std::size_t kdtree_get_point_count() const { return static_cast<std::size_t>(m->cols()); }
    double kdtree_get_pt(std::size_t i, std::size_t d) const {
      return (*m)(static_cast<Eigen::Index>(d), static_cast<Eigen::Index>(i));
    }
    template <class Box>
    bool kdtree_get_bbox(Box&) const { return false; }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, -1,
                                                   std::size_t>;
  Cloud cloud_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace errfield::detail
