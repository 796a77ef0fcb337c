// Linear model of coregionalization: validation, evaluation and the JSON form.

#include "errfield/coregionalization_model.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "errfield/error.hpp"
#include "errfield/json_file.hpp"

namespace errfield {

namespace {

std::string lmc_structure_name(const CoregionalizationStructure& s, std::size_t k) {
  return "LMC structure " + std::to_string(k) + " (" + std::string(model_kind_name(s.kind)) + ")";
}

ModelComponent lmc_unit_component(const CoregionalizationStructure& s) {
  return ModelComponent{.kind = s.kind, .sill = 1.0, .range = s.range, .nu = s.nu};
}

}  // namespace

double CoregionalizationStructure::unit_gamma(double h) const { return lmc_unit_component(*this).gamma(h); }

CoregionalizationModel::CoregionalizationModel(std::vector<CoregionalizationStructure> structures,
                                               Anisotropy anisotropy, std::vector<std::string> component_names)
    : structures_(std::move(structures)), anisotropy_(std::move(anisotropy)), names_(std::move(component_names)) {
  if (structures_.empty()) throw ArgumentError("LMC: no structures; expected at least one (e.g. nug + sph)");
  components_ = static_cast<int>(structures_.front().sills.rows());
  if (components_ < 1) throw ArgumentError("LMC: structure 0 has an empty coregionalization matrix");
  for (std::size_t k = 0; k < structures_.size(); ++k) {
    const CoregionalizationStructure& s = structures_[k];
    const std::string where = lmc_structure_name(s, k);
    if (!s.bounded_kind())
      throw ArgumentError(where + ": unbounded structures (pow, lin) have no covariance; cokriging needs nug, sph, exp, gau, mat or wen");
    // Domain of range and nu, named as a variogram component would be.
    try {
      (void)VariogramModel({lmc_unit_component(s)});
    } catch (const ArgumentError& e) {
      throw ArgumentError(where + ": " + e.what());
    }
    if (s.sills.rows() != components_ || s.sills.cols() != components_)
      throw ArgumentError(where + ": coregionalization matrix is " + std::to_string(s.sills.rows()) + " x " +
                          std::to_string(s.sills.cols()) + "; expected " + std::to_string(components_) + " x " +
                          std::to_string(components_) + " like structure 0");
    if (!s.sills.allFinite()) throw ArgumentError(where + ": coregionalization matrix has a non-finite entry");
    const double scale = std::max(s.sills.cwiseAbs().maxCoeff(), 1e-300);
    for (int i = 0; i < components_; ++i)
      for (int j = i + 1; j < components_; ++j)
        if (std::abs(s.sills(i, j) - s.sills(j, i)) > 1e-9 * scale)
          throw ArgumentError(where + ": coregionalization matrix is not symmetric: B(" + std::to_string(i) + "," +
                              std::to_string(j) + ") = " + std::to_string(s.sills(i, j)) + " but B(" +
                              std::to_string(j) + "," + std::to_string(i) + ") = " + std::to_string(s.sills(j, i)));
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(s.sills, Eigen::EigenvaluesOnly);
    const double smallest = eig.eigenvalues().minCoeff(), largest = eig.eigenvalues().cwiseAbs().maxCoeff();
    if (smallest < -1e-10 * largest)
      throw ArgumentError(where + ": coregionalization matrix is not positive semi-definite (smallest eigenvalue " +
                          std::to_string(smallest) + "); every LMC matrix must be, or cokriging variances can be negative");
  }
  if (!names_.empty() && static_cast<int>(names_.size()) != components_)
    throw ArgumentError("LMC: " + std::to_string(names_.size()) + " component names for " +
                        std::to_string(components_) + " components");
}

CoregionalizationModel CoregionalizationModel::intrinsic(const VariogramModel& shared,
                                                         const Eigen::MatrixXd& coregionalization,
                                                         std::vector<std::string> component_names) {
  std::vector<CoregionalizationStructure> s;
  for (const ModelComponent& c : shared.components())
    s.push_back({.kind = c.kind, .range = c.range, .nu = c.nu, .sills = c.sill * coregionalization});
  return CoregionalizationModel(std::move(s), shared.anisotropy(), std::move(component_names));
}

double CoregionalizationModel::gamma(int i, int j, double h) const {
  double g = 0.0;
  for (const auto& s : structures_) g += s.sills(i, j) * s.unit_gamma(h);
  return g;
}

Eigen::MatrixXd CoregionalizationModel::gamma_matrix(double h) const {
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(components_, components_);
  for (const auto& s : structures_) g += s.unit_gamma(h) * s.sills;
  return g;
}

Eigen::MatrixXd CoregionalizationModel::covariance_matrix(double h) const {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(components_, components_);
  for (const auto& s : structures_) c += (1.0 - s.unit_gamma(h)) * s.sills;
  return c;
}

Eigen::MatrixXd CoregionalizationModel::sill() const {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(components_, components_);
  for (const auto& s : structures_) c += s.sills;
  return c;
}

Eigen::MatrixXd CoregionalizationModel::nugget() const {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(components_, components_);
  for (const auto& s : structures_)
    if (s.kind == ModelKind::Nugget) c += s.sills;
  return c;
}

VariogramModel CoregionalizationModel::direct_model(int i) const {
  if (i < 0 || i >= components_)
    throw ArgumentError("LMC: component " + std::to_string(i) + " does not exist (the model has " +
                        std::to_string(components_) + ")");
  std::vector<ModelComponent> c;
  for (const auto& s : structures_) {
    ModelComponent m = lmc_unit_component(s);
    m.sill = std::max(0.0, s.sills(i, i));
    c.push_back(m);
  }
  return VariogramModel(std::move(c), anisotropy_);
}

std::string CoregionalizationModel::to_string() const {
  std::ostringstream o;
  o.precision(6);
  for (std::size_t k = 0; k < structures_.size(); ++k) {
    const auto& s = structures_[k];
    if (k) o << '\n';
    o << model_kind_name(s.kind);
    if (s.kind != ModelKind::Nugget) {
      o << "(range=" << s.range;
      if (s.kind == ModelKind::Matern) o << ",nu=" << s.nu;
      o << ')';
    }
    o << " B=[";
    for (int i = 0; i < components_; ++i) {
      o << (i ? ",[" : "[");
      for (int j = 0; j < components_; ++j) o << (j ? "," : "") << s.sills(i, j);
      o << ']';
    }
    o << ']';
  }
  if (!anisotropy_.isotropic()) o << "\n@" << anisotropy_.to_string();
  return o.str();
}

void to_json(nlohmann::json& j, const CoregionalizationModel& model) {
  j = nlohmann::json::object();
  j["type"] = "lmc";
  if (!model.component_names().empty()) j["components"] = model.component_names();
  auto& arr = j["structures"] = nlohmann::json::array();
  for (const auto& s : model.structures()) {
    nlohmann::json e{{"kind", std::string(model_kind_name(s.kind))}};
    if (s.kind != ModelKind::Nugget) e["range"] = s.range;
    if (s.kind == ModelKind::Matern) e["nu"] = s.nu;
    auto& rows = e["sills"] = nlohmann::json::array();
    for (Eigen::Index i = 0; i < s.sills.rows(); ++i) {
      nlohmann::json row = nlohmann::json::array();
      for (Eigen::Index c = 0; c < s.sills.cols(); ++c) row.push_back(s.sills(i, c));
      rows.push_back(std::move(row));
    }
    arr.push_back(std::move(e));
  }
  const Anisotropy& a = model.anisotropy();
  if (!a.isotropic()) j["anisotropy"] = {{a.type() == Anisotropy::Type::Ard ? "ard" : "anis", a.parameters()}};
}

bool is_coregionalization_json(const nlohmann::json& j) {
  return j.is_object() && j.contains("type") && j["type"].is_string() && j["type"].get<std::string>() == "lmc";
}

void from_json(const nlohmann::json& j, CoregionalizationModel& model) {
  if (!is_coregionalization_json(j))
    throw ArgumentError("LMC JSON: expected an object with \"type\": \"lmc\" (a single variogram model is not an LMC)");
  if (!j.contains("structures") || !j["structures"].is_array())
    throw ArgumentError("LMC JSON: expected a 'structures' array");
  std::vector<CoregionalizationStructure> structures;
  for (std::size_t k = 0; k < j["structures"].size(); ++k) {
    const auto& e = j["structures"][k];
    const std::string where = "LMC JSON: structures[" + std::to_string(k) + "]";
    if (!e.is_object() || !e.contains("kind") || !e["kind"].is_string())
      throw ArgumentError(where + ": expected an object with a string 'kind'");
    CoregionalizationStructure s;
    s.kind = model_kind_from_name(e["kind"].get<std::string>());
    auto number = [&](const char* key) -> double {
      if (!e.contains(key) || !e[key].is_number()) throw ArgumentError(where + ": missing or non-numeric '" + key + "'");
      return e[key].get<double>();
    };
    if (s.kind != ModelKind::Nugget) s.range = number("range");
    if (s.kind == ModelKind::Matern) s.nu = number("nu");
    if (!e.contains("sills") || !e["sills"].is_array() || e["sills"].empty())
      throw ArgumentError(where + ": expected 'sills', a square array of arrays of numbers");
    const auto& rows = e["sills"];
    const auto p = static_cast<Eigen::Index>(rows.size());
    s.sills.resize(p, p);
    for (Eigen::Index i = 0; i < p; ++i) {
      const auto& row = rows[static_cast<std::size_t>(i)];
      if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != p)
        throw ArgumentError(where + ": sills row " + std::to_string(i) + " is not an array of " + std::to_string(p) + " numbers");
      for (Eigen::Index c = 0; c < p; ++c) {
        if (!row[static_cast<std::size_t>(c)].is_number())
          throw ArgumentError(where + ": sills[" + std::to_string(i) + "][" + std::to_string(c) + "] is not a number");
        s.sills(i, c) = row[static_cast<std::size_t>(c)].get<double>();
      }
    }
    structures.push_back(std::move(s));
  }
  std::vector<std::string> names;
  if (j.contains("components")) {
    if (!j["components"].is_array()) throw ArgumentError("LMC JSON: 'components' must be an array of names");
    for (const auto& n : j["components"]) {
      if (!n.is_string()) throw ArgumentError("LMC JSON: 'components' must be an array of names");
      names.push_back(n.get<std::string>());
    }
  }
  Anisotropy anisotropy;
  if (j.contains("anisotropy")) {
    // The same form as a variogram model's: reuse its reader.
    nlohmann::json probe{{"components", nlohmann::json::array({{{"kind", "nug"}, {"sill", 0.0}}})},
                         {"anisotropy", j["anisotropy"]}};
    try {
      anisotropy = probe.get<VariogramModel>().anisotropy();
    } catch (const ArgumentError& e) {
      throw ArgumentError(std::string("LMC JSON: ") + e.what());
    }
  }
  model = CoregionalizationModel(std::move(structures), std::move(anisotropy), std::move(names));
}

CoregionalizationModel load_coregionalization_model(std::string_view path) {
  const std::string s(path);
  const nlohmann::json j = read_json_file(s, "LMC model JSON");
  try {
    return with_json_source(s, [&] { return j.get<CoregionalizationModel>(); });
  } catch (const ArgumentError& e) {
    throw InputError(s + ": " + e.what(), s);
  }
}

}  // namespace errfield
