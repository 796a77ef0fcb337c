#pragma once
// NumPy <-> Eigen at the Python boundary: every array argument is checked here so that a bad
// shape, a non-finite number or a wrong dtype raises a Python exception naming the argument
// (errfield.ArgumentError, a ValueError, for shapes and values; TypeError for dtypes).

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace errfield {
class CsvTable;
namespace robot {
class MdhModel;
}
}  // namespace errfield

namespace errfield::python {

namespace py = pybind11;

/// What an array argument must look like.
struct ArraySpec {
  int min_ndim = 1;                ///< 1-D arrays become one column (N,) -> N x 1 ...
  int max_ndim = 2;
  Eigen::Index cols = -1;          ///< required number of columns of a 2-D array; -1 = any
  Eigen::Index min_rows = 1;
  bool finite = true;              ///< reject NaN and infinities, naming the element
  bool one_d_is_row = false;       ///< ... unless set: then (C,) is one row 1 x C (a single joint vector)
};

/// A checked argument: the data (rows x cols, copied into column-major storage for the library)
/// and whether it came as a 1-D array (results then drop the same axis).
struct MatrixArg {
  Eigen::MatrixXd data;
  bool one_d = false;
};

MatrixArg matrix_arg(const py::handle& object, const std::string& name, const ArraySpec& spec = {});

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A checked argument read in place: a C-contiguous float64 array is not copied (`data` views its
/// buffer, `array` keeps it alive); anything else (other dtype, order or a list) is converted
/// once by NumPy. Checked as matrix_arg (shape, finiteness). The caller must not keep `data`
/// beyond `array`, and another thread mutating the array while the GIL is released is a race, as
/// in NumPy itself.
struct RowsArg {
  RowsArg(py::array_t<double, py::array::c_style> a, Eigen::Index rows, Eigen::Index cols, bool one_d_)
      : array(std::move(a)), data(array.data(), rows, cols), one_d(one_d_) {}
  py::array_t<double, py::array::c_style> array;
  Eigen::Map<const RowMatrixXd> data;
  bool one_d = false;
};
RowsArg rows_arg(const py::handle& object, const std::string& name, const ArraySpec& spec = {});

/// How many array arguments the module has copied so far (NumPy conversions of a non-float64 or
/// non-C-ordered argument, and matrix_arg's column-major copies): errfield._input_copies(), for
/// tests that an argument was read in place.
std::size_t input_copies();

/// A 1-D float64 vector argument (e.g. bin edges); `min_size` elements at least.
std::vector<double> vector_arg(const py::handle& object, const std::string& name, std::size_t min_size = 1,
                               bool finite = true);

/// The object as a float64 C-ordered array of any shape (integers convert); TypeError naming
/// `name` for other dtypes. For arguments whose shape matrix_arg cannot describe (N x 4 x 4 poses).
py::array_t<double, py::array::c_style> float_array(const py::handle& object, const std::string& name);

/// Copies into new NumPy arrays (C order). A matrix with `squeeze_cols` and one column becomes 1-D.
py::array_t<double> to_numpy(const Eigen::MatrixXd& m, bool squeeze_cols = false);
py::array_t<double> to_numpy(const std::vector<double>& v);
py::array_t<std::uint64_t> to_numpy(const std::vector<std::uint64_t>& v);

/// True for a dict-like of columns (has items(), not an array): a dict, a pandas DataFrame.
bool is_columns(const py::handle& object);

/// A dict of columns (name -> 1-D array; numbers, or text such as point and kind) as the CsvTable
/// the CLI reads from the same CSV, `name` as its source in messages. Numbers go through their
/// shortest round-trip text, so the table holds the same doubles; NaN is an empty cell.
CsvTable table_arg(const py::handle& data, const std::string& name);

/// None: the built-in ER20-C10 (the CLI without --robot); a Robot; a built-in name or a robot JSON
/// path (a file of a built-in's name wins, as in the CLI).
robot::MdhModel robot_arg(const py::object& robot);

}  // namespace errfield::python
