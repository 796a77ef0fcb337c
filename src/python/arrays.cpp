#include "python/arrays.hpp"

#include <atomic>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/robot/builtin_robots.hpp"
#include "errfield/robot/mdh_model.hpp"

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

namespace {

std::atomic<std::size_t> g_input_copies{0};

// The checked float64 C-ordered array of an argument and its shape as rows x cols; no copy when
// the object already is such an array (NumPy returns it as it is), else one conversion, counted.
struct Checked {
  py::array_t<double, py::array::c_style> array;
  Eigen::Index rows = 0, cols = 0;
  bool one_d = false;
};

Checked checked_array(const py::handle& object, const std::string& name, const ArraySpec& spec) {
  Checked c;
  c.array = as_float_array(object, name);
  if (c.array.ptr() != object.ptr()) ++g_input_copies;
  const auto& a = c.array;
  const auto nd = static_cast<int>(a.ndim());
  if (nd < spec.min_ndim || nd > spec.max_ndim) {
    std::string expected = spec.min_ndim == spec.max_ndim ? std::to_string(spec.min_ndim) + "-D"
                                                          : std::to_string(spec.min_ndim) + "-D or " +
                                                                std::to_string(spec.max_ndim) + "-D";
    throw ArgumentError(name + ": array of shape " + shape_text(a) + " is " + std::to_string(nd) + "-D; expected " +
                        expected);
  }
  c.one_d = nd == 1;
  if (nd == 1) {
    c.rows = spec.one_d_is_row ? 1 : static_cast<Eigen::Index>(a.shape(0));
    c.cols = spec.one_d_is_row ? static_cast<Eigen::Index>(a.shape(0)) : 1;
  } else {
    c.rows = static_cast<Eigen::Index>(a.shape(0));
    c.cols = static_cast<Eigen::Index>(a.shape(1));
  }
  if (spec.cols >= 0 && c.cols != spec.cols)
    throw ArgumentError(name + ": array of shape " + shape_text(a) + " has " + std::to_string(c.cols) +
                        (spec.one_d_is_row && nd == 1 ? " elements" : " columns") + "; expected " +
                        std::to_string(spec.cols));
  if (c.rows < spec.min_rows)
    throw ArgumentError(name + ": array of shape " + shape_text(a) + " has " + std::to_string(c.rows) +
                        " rows; expected at least " + std::to_string(spec.min_rows));
  if (spec.finite) {
    const double* p = a.data();
    for (Eigen::Index r = 0; r < c.rows; ++r)
      for (Eigen::Index k = 0; k < c.cols; ++k) {
        const double v = p[r * c.cols + k];
        if (std::isfinite(v)) continue;
        const std::string where = nd == 1 ? "[" + std::to_string(spec.one_d_is_row ? k : r) + "]"
                                          : "[" + std::to_string(r) + ", " + std::to_string(k) + "]";
        throw ArgumentError(name + where + " is " + number_text(v) + "; expected a finite number");
      }
  }
  return c;
}

}  // namespace

std::size_t input_copies() { return g_input_copies.load(); }

MatrixArg matrix_arg(const py::handle& object, const std::string& name, const ArraySpec& spec) {
  const Checked c = checked_array(object, name, spec);
  MatrixArg out;
  out.one_d = c.one_d;
  // Column-major storage for the library: a copy, counted.
  out.data = Eigen::Map<const RowMatrixXd>(c.array.data(), c.rows, c.cols);
  ++g_input_copies;
  return out;
}

RowsArg rows_arg(const py::handle& object, const std::string& name, const ArraySpec& spec) {
  Checked c = checked_array(object, name, spec);
  return RowsArg(std::move(c.array), c.rows, c.cols, c.one_d);
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

bool is_columns(const py::handle& o) { return py::hasattr(o, "items") && !py::isinstance<py::array>(o); }

/// A dict of columns as the CsvTable the CLI would read from the same CSV: numbers in shortest
/// round-trip form (so the table holds the same doubles), NaN as an empty cell, text as it is.
CsvTable table_arg(const py::handle& data, const std::string& name) {
  if (!is_columns(data))
    throw ArgumentError(name + ": expected a dict of columns (name -> 1-D array), e.g. the columns of "
                        "`errfield simulate`; got " + std::string(py::str(py::type::of(data).attr("__name__"))));
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> cells;
  for (const auto item : data.attr("items")()) {
    const auto kv = item.cast<py::tuple>();
    const std::string col = py::str(kv[0]);
    if (col.empty() || col.find_first_of(",\"\n\r") != std::string::npos)
      throw ArgumentError(name + ": column name '" + col + "' is empty or holds a comma, quote or newline");
    const py::array a = py::array::ensure(kv[1]);
    if (!a || a.ndim() != 1) throw ArgumentError(name + "['" + col + "']: expected a 1-D column");
    std::vector<std::string> c(static_cast<std::size_t>(a.size()));
    const char k = a.dtype().kind();
    if (k == 'f' || k == 'i' || k == 'u' || k == 'b') {
      const auto v = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
      for (std::size_t i = 0; i < c.size(); ++i) {
        const double x = v.data()[i];
        if (std::isinf(x))
          throw ArgumentError(name + "['" + col + "'][" + std::to_string(i) + "] is " + format_number(x) +
                              "; expected a finite number (NaN for an empty cell)");
        if (!std::isnan(x)) c[i] = format_number(x);
      }
    } else {
      for (std::size_t i = 0; i < c.size(); ++i) {
        c[i] = py::str(a[py::int_(i)]);
        if (c[i].find_first_of(",\"\n\r") != std::string::npos)
          throw ArgumentError(name + "['" + col + "'][" + std::to_string(i) + "]: '" + c[i] +
                              "' holds a comma, quote or newline");
      }
    }
    if (!cells.empty() && c.size() != cells.front().size())
      throw ArgumentError(name + "['" + col + "']: " + std::to_string(c.size()) + " rows but '" + names.front() +
                          "' has " + std::to_string(cells.front().size()) + "; expected columns of one length");
    names.push_back(col);
    cells.push_back(std::move(c));
  }
  if (names.empty()) throw ArgumentError(name + ": no columns");
  std::string text;
  for (std::size_t j = 0; j < names.size(); ++j) text += (j ? "," : "") + names[j];
  text += "\n";
  for (std::size_t i = 0; i < cells.front().size(); ++i) {
    for (std::size_t j = 0; j < names.size(); ++j) text += (j ? "," : "") + cells[j][i];
    text += "\n";
  }
  return CsvTable::parse(text, name);
}

/// None: the built-in ER20-C10 (as the CLI without --robot); a Robot; a built-in name or a robot
/// JSON path (a file of a built-in's name wins, as in the CLI).
robot::MdhModel robot_arg(const py::object& r) {
  if (r.is_none()) return robot::MdhModel::er20_c10();
  if (py::isinstance<robot::MdhModel>(r)) return r.cast<robot::MdhModel>();
  const std::string path = py::str(r);
  if (const robot::BuiltinRobot* b = robot::find_builtin_robot(path); b && !std::filesystem::exists(path)) return b->model;
  if (!std::filesystem::exists(path))
    throw InputError("robot '" + path + "': no such file and not a built-in robot (" + robot::builtin_robot_names() + ")",
                     path);
  return robot::MdhModel::load(path);
}

}  // namespace errfield::python
