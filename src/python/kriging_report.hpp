#pragma once
// How Kriging and Cokriging in Python surface the KrigingReport and per-target failures: a failed
// factorization raises, a usable one with a note (jitter, ...) and targets that could not be
// solved warn (RuntimeWarning), and report() returns the report as a dict.

#include <cstddef>
#include <string>

#include <pybind11/pybind11.h>

#include "errfield/error.hpp"
#include "errfield/kriging.hpp"

namespace errfield::python {

/// After construction: raises "<what> failed: <status>: <message>" when the system is unusable,
/// warns "<status>: <message>" when it is usable with a message. `what` is "kriging" or "cokriging".
inline void raise_or_warn(const KrigingReport& rep, const std::string& what) {
  if (!rep.usable()) throw Error(what + " failed: " + std::string(kriging_status_name(rep.status)) + ": " + rep.message);
  if (!rep.message.empty()) {
    const std::string w = std::string(kriging_status_name(rep.status)) + ": " + rep.message;
    if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) != 0) throw pybind11::error_already_set();
  }
}

/// After a prediction: warns "<failed> of <targets> targets could not be <verb> (<status>); their
/// <outputs> are NaN" when any target failed. verb: "kriged" or "cokriged"; outputs: "predictions", "draws".
inline void warn_failed_targets(std::size_t failed, std::size_t targets, KrigingStatus status, const std::string& verb,
                                const std::string& outputs) {
  if (failed == 0) return;
  const std::string w = std::to_string(failed) + " of " + std::to_string(targets) + " targets could not be " + verb +
                        " (" + std::string(kriging_status_name(status)) + "); their " + outputs + " are NaN";
  if (PyErr_WarnEx(PyExc_RuntimeWarning, w.c_str(), 1) != 0) throw pybind11::error_already_set();
}

/// The fields of report() that Kriging and Cokriging share; each adds its own after them.
inline pybind11::dict report_dict(const KrigingReport& rep) {
  pybind11::dict d;
  d["status"] = std::string(kriging_status_name(rep.status));
  d["message"] = rep.message;
  d["condition_number"] = rep.condition_number;
  d["jitter"] = rep.jitter;
  d["samples_used"] = rep.samples_used;
  return d;
}

}  // namespace errfield::python
