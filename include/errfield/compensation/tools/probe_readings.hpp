#pragma once
/// Readings of a 6-DoF probe (a tracker's T-probe, T-Mac, 6DoF SMR): each row gives the probe
/// point's position mx,my,mz (tracker frame, mm) and the probe's orientation in the tracker frame,
/// either as `mrx,mry,mrz` (degrees, fixed-axis X-Y-Z as everywhere in errfield: R = Rz·Ry·Rx) or as
/// a unit quaternion `mqw,mqx,mqy,mqz`.
///
/// An orientation is what three points of a rigid body say: each probe row is turned into the
/// readings of three points on the flange, the probe point and two points kProbeLeverMm along the
/// probe's own x and y axes, labelled LABEL, LABEL+x and LABEL+y (LABEL: the row's `reflector`, or
/// "probe"). Every step that takes several points on the flange (fit, calibrate, validate's
/// orientation block) then takes probe data: the points are located from the data as reflectors
/// are, the orientation error is the flange rotation they imply (flange_rotation.hpp).
/// docs/data-formats.md, "6-DoF probe readings".

#include <string>

#include "errfield/csv_table.hpp"

namespace errfield::compensation {

/// The lever of the two points a probe row's orientation becomes (mm): long enough that a 0.01 deg
/// orientation reading moves them by 0.017 mm, the size of a tracker's position noise, and short
/// enough to stay on a flange-sized tool.
inline constexpr double kProbeLeverMm = 100.0;

/// True when `table` has orientation columns (mrx,mry,mrz or mqw,mqx,mqy,mqz).
bool has_probe_orientation(const CsvTable& table);

/// The table with each probe row as three point readings (see the file comment): the orientation
/// columns dropped, a `reflector` column added or relabelled, mx,my,mz of the two lever points
/// computed, every other cell copied, each row keeping its line number. A table without orientation
/// columns is returned as it is. Throws InputError naming file, line and column for a row with some
/// but not all of the orientation cells, a non-finite angle, a quaternion whose norm is not 1 within
/// 1e-3, or both orientation forms in one file.
CsvTable expand_probe_readings(const CsvTable& table);

}  // namespace errfield::compensation
