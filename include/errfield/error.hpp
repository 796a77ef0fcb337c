#pragma once
/// Exceptions errfield throws at its API boundary.
///
/// Use them for input the caller can fix (a malformed file, an out-of-range option). Numerical
/// outcomes the caller must decide about (a matrix that is not positive definite, an optimizer at
/// its iteration limit, an IK target out of reach) are returned as a status, not thrown.

#include <stdexcept>
#include <string>

namespace errfield {

/// Base of every exception errfield throws; catch this one to catch them all.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A function argument or option is out of its documented domain (bin width <= 0, k = 0, ...).
/// The message names the parameter, the value that came and what was expected.
class ArgumentError : public Error {
 public:
  using Error::Error;
};

/// Data read from a file or passed as samples is unusable. When it comes from a file, `file()`,
/// `row()` (1-based, counting the header as row 1) and `column()` say where; empty/0 when unknown.
class InputError : public Error {
 public:
  explicit InputError(const std::string& message, std::string file = {}, std::size_t row = 0,
                      std::string column = {})
      : Error(message), file_(std::move(file)), row_(row), column_(std::move(column)) {}
  const std::string& file() const noexcept { return file_; }
  std::size_t row() const noexcept { return row_; }
  const std::string& column() const noexcept { return column_; }

 private:
  std::string file_;
  std::size_t row_;
  std::string column_;
};

/// A requested job would exceed a resource budget (memory); the message names a cheaper way.
class ResourceError : public Error {
 public:
  using Error::Error;
};

}  // namespace errfield
