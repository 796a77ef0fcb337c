// `errfield register`: a model registered anew to tracker readings of another day (the tracker moved),
// everything it learned about the robot kept (compensation/fitting/re_registration.hpp).
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli/cli_support.hpp"
#include "cli/command_registry.hpp"
#include "cli/robot_cli.hpp"
#include "compensation/fitting/fit_checks.hpp"
#include "errfield/atomic_file.hpp"
#include "errfield/compensation/fitting/model_fitting.hpp"
#include "errfield/compensation/fitting/re_registration.hpp"
#include "errfield/compensation/model/prediction.hpp"
#include "errfield/compensation/pipeline.hpp"
#include "errfield/compensation/tools/probe_readings.hpp"
#include "errfield/error.hpp"
#include "errfield/json_file.hpp"
#include "errfield/number_format.hpp"

namespace errfield::cli {
namespace {

struct RegisterArgs {
  std::string model, data, reflector, out;
  double outlier_sigmas = compensation::ReRegistrationOptions{}.outlier_sigmas;
};

void run_register(const RegisterArgs& a) {
  using namespace compensation;
  const LoadedModel loaded = load_model(a.model);
  if (!loaded.model.registration())
    throw InputError(a.model + ": has no registration to replace (a model fitted without tracker positions mx,my,mz, "
                     "or a robot JSON without a 'registration' member)",
                     a.model);
  CompensationModel model = loaded.model;
  // A 6-DoF probe's rows become three points on the flange; the model's own point's rows are used.
  const CsvTable file = expand_probe_readings(CsvTable::read(a.data));
  const CsvTable table = rows_of_one_reflector(file, a.reflector, false, model, "--");
  const robot::MdhModel nominal = nominal_at_working_tool(model, model.nominal_model());
  const MeasurementSet data = with_source(a.data, [&] { return MeasurementSet::from_table(table, nominal); });
  if (data.measured_mm.empty())
    throw InputError(a.data + ": no tracker positions (columns mx,my,mz): register maps readings onto the model", a.data);
  warn_if_metres(table, nominal, "register");
  ReRegistrationOptions options;
  options.outlier_sigmas = a.outlier_sigmas;
  // The nominal robot's own registration ('before' in validate) at the point the readings are of, as
  // fit and validate place it: at the robot JSON's tool, 16 mm from the real UR10's located T-Mac
  // point, the stored frame put validate's 'before' at 15.4 mm instead of 1.1.
  const robot::MdhModel nominal_at_readings = nominal_at_measured_point(model, model.nominal_model());
  const ReRegistration r = reregister(model, nominal_at_readings, data.q_deg, data.measured_mm, a.data, options);

  // Everything else in the file stays as written: only the two registrations and a note change.
  nlohmann::json j = read_json_file(a.model, "model file");
  j["registration"] = registration_to_json(r.registration);
  if (j.contains("nominal_registration") || j.contains("format"))
    j["nominal_registration"] = registration_to_json(r.nominal_registration);
  const std::string note = "registration replaced by 'errfield register' on " + std::to_string(r.registration.points) +
                           " readings of " + a.data + " (residual RMS " +
                           format_significant(r.registration.residual_rms_mm, 4) + " mm, " +
                           std::to_string(r.excluded.size()) + " left out)";
  if (j.contains("format")) j["notes"].push_back(note);

  std::cout << "register: " << loaded.description << " from " << a.model << " onto " << data.q_deg.size()
            << " readings of " << a.data << "\n"
            << "  registration tracker -> robot: residual RMS " << format_significant(r.registration.residual_rms_mm, 4)
            << " mm on " << r.registration.points << " readings (robust sd per axis "
            << format_significant(r.robust_sigma_mm, 3) << " mm); the nominal robot's own: "
            << format_significant(r.nominal_registration.residual_rms_mm, 4) << " mm\n";
  if (r.without_field > 0)
    std::cout << "  " << r.without_field << " of " << data.q_deg.size()
              << " readings lie outside the field's region: registered on the calibration and the joint error "
                 "functions alone there\n";
  for (const std::size_t i : r.excluded)
    std::cout << "  left out: point " << data.id[i] << ", " << format_significant(r.residual_mm[i], 4)
              << " mm off the rigid motion of the others\n";
  std::cout << "  model written to " << a.out << "\n";
  require_standard_output();
  write_file_atomically(a.out, j.dump(1) + "\n");
}

void add_register_command(CLI::App& app) {
  auto a = std::make_shared<RegisterArgs>();
  auto* cmd = app.add_subcommand(
      "register",
      "Register a model anew to tracker readings of another day (the tracker, or the robot, moved since the\n"
      "model was fitted). Everything the model learned about the robot (calibration, joint error functions,\n"
      "field) is kept; the tracker -> robot registration and the nominal robot's own ('before') are fitted\n"
      "anew on the readings (q1..q6 deg, mx,my,mz mm in the tracker frame; a 6-DoF probe's rows or a\n"
      "'reflector' column as fit reads them). 10-30 readings spread over the work volume are enough. Readings\n"
      "that do not fit one rigid motion are left out and listed; more than a fifth refuses the set (exit 2).\n"
      "Readings outside the model's field region are registered on the calibration and joint error functions.\n"
      "Example: errfield register --model model.json --data holdout.csv --out model_today.json");
  cmd->add_option("--model", a->model, "model JSON from 'errfield fit' (or a calibrated robot JSON with a registration)")
      ->required();
  cmd->add_option("--data", a->data, "readings of today: q1..q6 (deg), mx,my,mz (mm, tracker frame)")->required();
  cmd->add_option("--reflector", a->reflector,
                  "data of several points on the flange: the label to register with (default: the model's own point)");
  cmd->add_option("--outlier-sigmas", a->outlier_sigmas,
                  "leave out a reading whose 3-D residual is beyond this many robust sd per axis (4.03: 1 in 1000 "
                  "of Gaussian readings)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--out", a->out, "the model registered anew (JSON, written atomically; may be --model itself)")->required();
  cmd->callback([a] { run_register(*a); });
}

Registration register_register{"register", 76, &add_register_command};

}  // namespace
}  // namespace errfield::cli
