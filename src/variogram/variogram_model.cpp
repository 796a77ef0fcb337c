#include "errfield/variogram_model.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield {
namespace {

constexpr ModelKind kAllKinds[] = {ModelKind::Nugget,   ModelKind::Spherical, ModelKind::Exponential,
                                   ModelKind::Gaussian, ModelKind::Matern,    ModelKind::Wendland,
                                   ModelKind::Power,    ModelKind::Linear};

std::string describe(const ModelComponent& c, std::size_t index) {
  return "component " + std::to_string(index + 1) + " (" + std::string(model_kind_name(c.kind)) + ")";
}

void validate(const ModelComponent& c, std::size_t index) {
  auto fail = [&](const std::string& what, double v, const std::string& expected) {
    throw ArgumentError("variogram model " + describe(c, index) + ": " + what + " = " +
                        format_number(v) + "; expected " + expected);
  };
  if (!(c.sill >= 0.0) || !std::isfinite(c.sill)) fail("sill", c.sill, "a finite value >= 0");
  switch (c.kind) {
    case ModelKind::Nugget:
    case ModelKind::Linear:
      break;
    case ModelKind::Power:
      if (!(c.range > 0.0 && c.range < 2.0)) fail("exponent", c.range, "0 < exponent < 2");
      break;
    case ModelKind::Matern:
      // Beyond nu = 100 Gamma(nu) and K_nu(r) leave double range for ordinary lags (and libstdc++'s
      // K_nu throws for huge nu); such a model is flat at every practical lag anyway.
      if (!(c.nu > 0.0 && c.nu <= kMaxMaternNu)) fail("nu", c.nu, "0 < nu <= " + format_number(kMaxMaternNu));
      [[fallthrough]];
    default:
      if (!(c.range > 0.0) || !std::isfinite(c.range)) fail("range", c.range, "a finite value > 0");
  }
}

double parse_double(std::string_view text, std::string_view context) {
  double v = 0.0;
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;
  const auto res = std::from_chars(first, last, v);
  if (first == last || res.ec != std::errc() || res.ptr != last || !std::isfinite(v))
    throw ArgumentError("variogram model: '" + std::string(text) + "' in '" + std::string(context) +
                        "' is not a finite number");
  return v;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

ModelComponent parse_component(std::string_view term) {
  const std::string context(term);
  const auto open = term.find('(');
  if (open == std::string_view::npos || term.back() != ')')
    throw ArgumentError("variogram model: '" + context +
                        "' is not of the form kind(sill=S,range=A), e.g. sph(sill=0.3,range=400)");
  ModelComponent c;
  c.kind = model_kind_from_name(trim(term.substr(0, open)));
  c.range = 0.0;
  std::string_view args = term.substr(open + 1, term.size() - open - 2);
  // Positional order: sill, range (exponent for pow), nu.
  const char* positional_names[] = {c.kind == ModelKind::Linear ? "slope" : "sill",
                                     c.kind == ModelKind::Power ? "exponent" : "range", "nu"};
  bool seen[3] = {false, false, false};
  std::string seen_as[3];  // the key that set each slot, for the message when another sets it again
  std::size_t position = 0;
  while (!trim(args).empty()) {
    const auto comma = args.find(',');
    std::string_view item = trim(args.substr(0, comma));
    args = comma == std::string_view::npos ? std::string_view{} : args.substr(comma + 1);
    std::string_view key;
    std::string_view value = item;
    const auto eq = item.find('=');
    if (eq != std::string_view::npos) {
      key = trim(item.substr(0, eq));
      value = trim(item.substr(eq + 1));
    } else {
      if (position >= 3)
        throw ArgumentError("variogram model: too many arguments in '" + context + "'");
      key = positional_names[position];
    }
    ++position;
    int slot = -1;
    if (key == "sill" || key == "psill" || key == "slope") slot = 0;
    else if (key == "range" || key == "exponent" || key == "a") slot = 1;
    else if (key == "nu" || key == "kappa") slot = 2;
    else
      throw ArgumentError("variogram model: unknown parameter '" + std::string(key) + "' in '" +
                          context + "'; known: sill, range, nu (exponent for pow, slope for lin)");
    if (seen[slot])
      throw ArgumentError("variogram model: the " + std::string(positional_names[slot]) + " of '" + context +
                          "' is given twice" +
                          (seen_as[slot] == key ? std::string()
                                                : " (as '" + seen_as[slot] + "' and as '" + std::string(key) +
                                                      "', names of the same parameter)"));
    seen[slot] = true;
    seen_as[slot] = std::string(key);
    const double v = parse_double(value, context);
    if (slot == 0) c.sill = v;
    else if (slot == 1) c.range = v;
    else c.nu = v;
    if (comma == std::string_view::npos) break;
  }
  if (!seen[0])
    throw ArgumentError("variogram model: '" + context + "' has no sill");
  const bool needs_range = c.kind != ModelKind::Nugget && c.kind != ModelKind::Linear;
  if (needs_range && !seen[1])
    throw ArgumentError("variogram model: '" + context + "' has no " +
                        (c.kind == ModelKind::Power ? "exponent" : "range"));
  if (c.kind == ModelKind::Matern && !seen[2])
    throw ArgumentError("variogram model: '" + context + "' has no nu (Matérn smoothness)");
  return c;
}

}  // namespace

std::string_view model_kind_name(ModelKind kind) {
  switch (kind) {
    case ModelKind::Nugget: return "nug";
    case ModelKind::Spherical: return "sph";
    case ModelKind::Exponential: return "exp";
    case ModelKind::Gaussian: return "gau";
    case ModelKind::Matern: return "mat";
    case ModelKind::Wendland: return "wen";
    case ModelKind::Power: return "pow";
    case ModelKind::Linear: return "lin";
  }
  return "?";
}

ModelKind model_kind_from_name(std::string_view name) {
  std::string lower(name);
  for (auto& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (const ModelKind k : kAllKinds)
    if (model_kind_name(k) == lower) return k;
  throw ArgumentError("variogram model: unknown model '" + std::string(name) +
                      "'; known: nug, sph, exp, gau, mat, wen, pow, lin");
}

double ModelComponent::gamma(double h) const {
  if (h <= 0.0) return 0.0;
  switch (kind) {
    case ModelKind::Nugget:
      return sill;
    case ModelKind::Spherical: {
      if (h >= range) return sill;
      const double r = h / range;
      return sill * (1.5 * r - 0.5 * r * r * r);
    }
    case ModelKind::Exponential:
      return sill * -std::expm1(-h / range);
    case ModelKind::Gaussian: {
      const double r = h / range;
      return sill * -std::expm1(-r * r);
    }
    case ModelKind::Matern: {
      const double r = h / range;
      // K_nu underflows far out; the correlation is then 0 to double precision.
      if (r > 700.0) return sill;
      if (r < 1e-300) {
        // libstdc++'s K_nu throws for subnormal arguments. Leading term of the series:
        // 1 - rho = Gamma(1-nu)/Gamma(1+nu) (r/2)^(2 nu) for nu < 1 (still ~1e-6 at nu = 0.01);
        // for nu >= 1 it is O(r^2 log r), below 1e-590.
        // The fraction is formed before the sill multiplies it: sill * Gamma(1-nu) alone overflows
        // for sills near DBL_MAX, and inf * 0 (r underflowed to 0) would be NaN (found by fuzzing).
        if (nu >= 1.0) return 0.0;
        const double fraction = std::tgamma(1.0 - nu) / std::tgamma(1.0 + nu) * std::pow(r / 2.0, 2.0 * nu);
        return sill * std::min(fraction, 1.0);
      }
      // Half-integer nu (--model auto's mat(1.5) and mat(2.5), and 0.5 = exp): the closed forms of
      // 2^(1-nu)/Gamma(nu) r^nu K_nu(r). The Bessel function and Gamma were a third of an automatic
      // model choice's time at 1,000 samples (issue 49); the values agree to a few ulps.
      if (nu == 0.5) return sill * -std::expm1(-r);
      if (nu == 1.5) return sill * std::clamp(-std::expm1(-r) - r * std::exp(-r), 0.0, 1.0);
      if (nu == 2.5) return sill * std::clamp(-std::expm1(-r) - r * (1.0 + r / 3.0) * std::exp(-r), 0.0, 1.0);
      const double k = std::cyl_bessel_k(nu, r);
      if (!std::isfinite(k)) {
        // Near r = 0, K_nu(r) overflows while r^nu underflows (their product is finite). Use the
        // series of K_nu: 1 - rho = r^2/(4(nu-1)) - r^4/(32(nu-1)(nu-2)) + O(r^6, r^(2 nu)). The
        // overflow needs r < ~0.06 at nu = 100, r < 1e-14 at nu = 20, r < 1e-150 at nu <= 2 and
        // r < 1e-300 (handled above) at nu <= 1, so the terms kept are exact to double precision.
        if (nu <= 1.0) return 0.0;
        const double r2 = r * r;
        const double lead = r2 / (4.0 * (nu - 1.0));
        return sill * (nu > 2.0 ? lead - r2 * r2 / (32.0 * (nu - 1.0) * (nu - 2.0)) : lead);
      }
      // The direct product is the most accurate (absolute error a few ulps of 1); nu <= 100 keeps
      // 2^(1-nu)/Gamma(nu) in range. If r^nu or the product leaves double range, fall back to logs.
      const double coef = std::pow(2.0, 1.0 - nu) / std::tgamma(nu);
      const double p = std::pow(r, nu);
      double corr = coef * k * p;
      if (!(p > 0.0) || !std::isfinite(corr))
        corr = k > 0.0 ? std::exp(std::log(coef) + std::log(k) + nu * std::log(r)) : 0.0;
      return sill * std::clamp(1.0 - corr, 0.0, 1.0);
    }
    case ModelKind::Wendland: {
      if (h >= range) return sill;
      // 1 - (1-r)^4 (4r+1) expanded: r^2 (10 - 20r + 15r^2 - 4r^3), which is > 0 on (0, 1) in
      // floating point too (the unexpanded form rounds to -1 ulp near r = 0; found by fuzzing).
      const double r = h / range;
      return sill * r * r * (10.0 + r * (-20.0 + r * (15.0 - 4.0 * r)));
    }
    case ModelKind::Power:
      return sill * std::pow(h, range);
    case ModelKind::Linear:
      return sill * h;
  }
  return 0.0;
}

VariogramModel::VariogramModel(std::vector<ModelComponent> components, Anisotropy anisotropy)
    : components_(std::move(components)), anisotropy_(std::move(anisotropy)) {
  if (components_.empty()) throw ArgumentError("variogram model: no components");
  for (std::size_t i = 0; i < components_.size(); ++i) validate(components_[i], i);
}

VariogramModel VariogramModel::parse(std::string_view full_text) {
  std::string_view text = full_text;
  Anisotropy anisotropy;
  if (const auto at = full_text.find('@'); at != std::string_view::npos) {
    text = full_text.substr(0, at);
    anisotropy = Anisotropy::parse(full_text.substr(at + 1));
  }
  std::vector<ModelComponent> components;
  int depth = 0;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i < text.size() && text[i] == '(') ++depth;
    if (i < text.size() && text[i] == ')') --depth;
    if (depth < 0)
      throw ArgumentError("variogram model: unbalanced ')' in '" + std::string(text) + "'");
    // '+' inside parentheses belongs to a number ("1e+3"); only depth-0 '+' joins components.
    if (i == text.size() || (text[i] == '+' && depth == 0)) {
      const std::string_view term = trim(text.substr(start, i - start));
      if (term.empty())
        throw ArgumentError("variogram model: empty term in '" + std::string(text) +
                            "'; expected e.g. sph(sill=0.3,range=400)+nug(0.002)");
      components.push_back(parse_component(term));
      start = i + 1;
    }
  }
  if (depth != 0) throw ArgumentError("variogram model: unbalanced '(' in '" + std::string(text) + "'");
  return VariogramModel(std::move(components), std::move(anisotropy));
}

std::string VariogramModel::to_string() const {
  std::string out;
  for (const auto& c : components_) {
    if (!out.empty()) out += "+";
    out += model_kind_name(c.kind);
    switch (c.kind) {
      case ModelKind::Nugget: out += "(sill=" + format_number(c.sill) + ")"; break;
      case ModelKind::Linear: out += "(slope=" + format_number(c.sill) + ")"; break;
      case ModelKind::Power:
        out += "(sill=" + format_number(c.sill) + ",exponent=" + format_number(c.range) + ")";
        break;
      case ModelKind::Matern:
        out += "(sill=" + format_number(c.sill) + ",range=" + format_number(c.range) +
               ",nu=" + format_number(c.nu) + ")";
        break;
      default:
        out += "(sill=" + format_number(c.sill) + ",range=" + format_number(c.range) + ")";
    }
  }
  if (!anisotropy_.isotropic()) out += "@" + anisotropy_.to_string();
  return out;
}

double VariogramModel::gamma(double h) const {
  double g = 0.0;
  for (const auto& c : components_) g += c.gamma(h);
  return g;
}

double VariogramModel::sill() const {
  double s = 0.0;
  for (const auto& c : components_) s += c.sill;
  return s;
}

double VariogramModel::nugget() const {
  double s = 0.0;
  for (const auto& c : components_)
    if (c.kind == ModelKind::Nugget) s += c.sill;
  return s;
}

bool VariogramModel::bounded() const {
  for (const auto& c : components_)
    if (!c.bounded()) return false;
  return true;
}

bool VariogramModel::compact() const {
  for (const auto& c : components_)
    if (c.kind != ModelKind::Nugget && !c.compact()) return false;
  return true;
}

double VariogramModel::support() const {
  if (!compact()) return std::numeric_limits<double>::infinity();
  double r = 0.0;
  for (const auto& c : components_)
    if (c.kind != ModelKind::Nugget) r = std::max(r, c.range);
  return r;
}

void to_json(nlohmann::json& j, const VariogramModel& model) {
  j = nlohmann::json::object();
  auto& arr = j["components"] = nlohmann::json::array();
  for (const auto& c : model.components()) {
    nlohmann::json e{{"kind", std::string(model_kind_name(c.kind))}, {"sill", c.sill}};
    if (c.kind == ModelKind::Power) e["exponent"] = c.range;
    else if (c.kind != ModelKind::Nugget && c.kind != ModelKind::Linear) e["range"] = c.range;
    if (c.kind == ModelKind::Matern) e["nu"] = c.nu;
    arr.push_back(std::move(e));
  }
  const Anisotropy& a = model.anisotropy();
  if (!a.isotropic()) j["anisotropy"] = {{a.type() == Anisotropy::Type::Ard ? "ard" : "anis", a.parameters()}};
  j["expression"] = model.to_string();
}

void from_json(const nlohmann::json& j, VariogramModel& model) {
  if (!j.is_object() || !j.contains("components") || !j["components"].is_array())
    throw ArgumentError("variogram model JSON: expected an object with a 'components' array");
  std::vector<ModelComponent> components;
  std::size_t index = 0;
  for (const auto& e : j["components"]) {
    ++index;
    const std::string where = "variogram model JSON: components[" + std::to_string(index - 1) + "]";
    auto number = [&](const char* key) -> double {
      if (!e.contains(key) || !e[key].is_number())
        throw ArgumentError(where + ": missing or non-numeric '" + key + "'");
      return e[key].get<double>();
    };
    if (!e.is_object() || !e.contains("kind") || !e["kind"].is_string())
      throw ArgumentError(where + ": expected an object with a string 'kind'");
    ModelComponent c;
    c.kind = model_kind_from_name(e["kind"].get<std::string>());
    c.sill = number("sill");
    if (c.kind == ModelKind::Power) c.range = number("exponent");
    else if (c.kind != ModelKind::Nugget && c.kind != ModelKind::Linear) c.range = number("range");
    if (c.kind == ModelKind::Matern) c.nu = number("nu");
    components.push_back(c);
  }
  Anisotropy anisotropy;
  if (j.contains("anisotropy")) {
    const auto& a = j["anisotropy"];
    auto numbers = [&](const char* key) {
      if (!a[key].is_array()) throw ArgumentError(std::string("variogram model JSON: anisotropy.") + key + ": expected an array of numbers");
      std::vector<double> v;
      for (const auto& x : a[key]) {
        if (!x.is_number()) throw ArgumentError(std::string("variogram model JSON: anisotropy.") + key + ": expected numbers");
        v.push_back(x.get<double>());
      }
      return v;
    };
    if (!a.is_object() || a.size() != 1 || !(a.contains("ard") || a.contains("anis")))
      throw ArgumentError("variogram model JSON: 'anisotropy' must be {\"ard\": [...]} or {\"anis\": [...]}");
    anisotropy = a.contains("ard") ? Anisotropy::ard(numbers("ard")) : Anisotropy::rotated(numbers("anis"));
  }
  model = VariogramModel(std::move(components), std::move(anisotropy));
}

VariogramModel load_variogram_model(std::string_view text_or_file) {
  const std::string s(text_or_file);
  if (s.size() < 5 || s.compare(s.size() - 5, 5, ".json") != 0) return VariogramModel::parse(s);
  std::ifstream in(s);
  if (!in) throw InputError(s + ": cannot open the model JSON", s);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(s + ": not valid JSON (" + e.what() + ")", s);
  }
  try {
    return j.get<VariogramModel>();
  } catch (const ArgumentError& e) {
    throw InputError(s + ": " + e.what(), s);
  }
}

}  // namespace errfield
