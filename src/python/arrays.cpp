#include "python/arrays.hpp"

#include <cmath>
#include <sstream>

#include "errfield/error.hpp"

namespace errfield::python {

namespace {

std::string shape_text(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t k = 0; k < a.ndim(); ++k) s << (k ? ", " : "") << a.shape(k);
  s << (a.ndim() == 1 ? ",)" : ")");
  return s.str();
}

std::string number_text(double v) {
  if (std::isnan(v)) return "nan";
  return v > 0 ? "inf" : "-inf";
}

// The object as a float64 C-ordered array. Integers convert (NumPy's own rule for float
// arguments); booleans, complex numbers, strings and objects are a TypeError naming the argument.
py::array_t<double, py::array::c_style> as_float_array(const py::handle& object, const std::string& name) {
  py::array any;
  if (py::isinstance<py::array>(object)) {
    any = py::reinterpret_borrow<py::array>(object);
  } else {
    any = py::array::ensure(object);
    if (!any)
      throw py::type_error(name + ": expected an array of numbers (NumPy array or nested sequence), got " +
                           std::string(py::str(py::type::of(object).attr("__name__"))));
  }
  const char kind = any.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(name + ": dtype " + std::string(py::str(any.dtype())) +
                         " is not a real number type; expected float64 (integer arrays are converted)");
  auto out = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(any);
  if (!out) throw py::type_error(name + ": cannot convert to float64");
  return out;
}

}  // namespace

py::array_t<double, py::array::c_style> float_array(const py::handle& object, const std::string& name) {
  return as_float_array(object, name);
}

MatrixArg matrix_arg(const py::handle& object, const std::string& name, const ArraySpec& spec) {
  const auto a = as_float_array(object, name);
  const auto nd = static_cast<int>(a.ndim());
  if (nd < spec.min_ndim || nd > spec.max_ndim) {
    std::string expected = spec.min_ndim == spec.max_ndim ? std::to_string(spec.min_ndim) + "-D"
                                                          : std::to_string(spec.min_ndim) + "-D or " +
                                                                std::to_string(spec.max_ndim) + "-D";
    throw ArgumentError(name + ": array of shape " + shape_text(a) + " is " + std::to_string(nd) + "-D; expected " +
                        expected);
  }
  MatrixArg out;
  out.one_d = nd == 1;
  Eigen::Index rows = 0, cols = 0;
  if (nd == 1) {
    rows = spec.one_d_is_row ? 1 : static_cast<Eigen::Index>(a.shape(0));
    cols = spec.one_d_is_row ? static_cast<Eigen::Index>(a.shape(0)) : 1;
  } else {
    rows = static_cast<Eigen::Index>(a.shape(0));
    cols = static_cast<Eigen::Index>(a.shape(1));
  }
  if (spec.cols >= 0 && cols != spec.cols)
    throw ArgumentError(name + ": array of shape " + shape_text(a) + " has " + std::to_string(cols) +
                        (spec.one_d_is_row && nd == 1 ? " elements" : " columns") + "; expected " +
                        std::to_string(spec.cols));
  if (rows < spec.min_rows)
    throw ArgumentError(name + ": array of shape " + shape_text(a) + " has " + std::to_string(rows) +
                        " rows; expected at least " + std::to_string(spec.min_rows));
  out.data.resize(rows, cols);
  const double* p = a.data();
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::Index c = 0; c < cols; ++c) {
      const double v = p[r * cols + c];
      if (spec.finite && !std::isfinite(v)) {
        const std::string where = nd == 1 ? "[" + std::to_string(nd == 1 && spec.one_d_is_row ? c : r) + "]"
                                          : "[" + std::to_string(r) + ", " + std::to_string(c) + "]";
        throw ArgumentError(name + where + " is " + number_text(v) + "; expected a finite number");
      }
      out.data(r, c) = v;
    }
  return out;
}

std::vector<double> vector_arg(const py::handle& object, const std::string& name, std::size_t min_size, bool finite) {
  ArraySpec spec;
  spec.max_ndim = 1;
  spec.min_rows = static_cast<Eigen::Index>(min_size);
  spec.finite = finite;
  const MatrixArg m = matrix_arg(object, name, spec);
  return std::vector<double>(m.data.data(), m.data.data() + m.data.size());
}

py::array_t<double> to_numpy(const Eigen::MatrixXd& m, bool squeeze_cols) {
  if (squeeze_cols && m.cols() == 1) {
    py::array_t<double> out(static_cast<py::ssize_t>(m.rows()));
    auto w = out.mutable_unchecked<1>();
    for (Eigen::Index r = 0; r < m.rows(); ++r) w(r) = m(r, 0);
    return out;
  }
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto w = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) w(r, c) = m(r, c);
  return out;
}

py::array_t<double> to_numpy(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

py::array_t<std::uint64_t> to_numpy(const std::vector<std::uint64_t>& v) {
  py::array_t<std::uint64_t> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

}  // namespace errfield::python
