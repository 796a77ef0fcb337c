#pragma once
// One function per area of the module, called by module.cpp in this order.

#include <pybind11/pybind11.h>

namespace errfield::python {

void bind_variogram(pybind11::module_& m);       // variogram, VariogramModel, fits (bind_variogram.cpp)
void bind_interpolation(pybind11::module_& m);   // Kriging, ScatteredIdw, GridIdw (bind_interpolation.cpp)
void bind_cokriging(pybind11::module_& m);       // Cokriging (bind_cokriging.cpp)
void bind_robot(pybind11::module_& m);           // Robot: FK, IK, Jacobians, JSON (bind_robot.cpp)
void bind_calibration(pybind11::module_& m);     // calibrate_positions (bind_calibration.cpp), after Robot
void bind_pipeline(pybind11::module_& m);        // fit, predict, compensate, validate (bind_pipeline.cpp), after Robot

}  // namespace errfield::python
