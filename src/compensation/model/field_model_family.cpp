#include "errfield/compensation/model/field_model_family.hpp"

#include <cmath>
#include <regex>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"

namespace errfield::compensation {

std::string FieldModelFamily::to_string() const {
  std::string s(model_kind_name(kind));
  if (nu) s += "(" + format_number(*nu) + ")";
  if (ard) s += *ard ? "@ard" : "@iso";
  return s;
}

std::optional<FieldModelFamily> parse_field_model_family(std::string_view text) {
  static const std::regex family(R"(^\s*([a-z]+)\s*(\(\s*(?:nu\s*=\s*)?([0-9.eE+-]*)\s*\))?\s*(\+\s*nug)?\s*(@(iso|ard))?\s*$)");
  std::cmatch m;
  const std::string t(text);
  if (!std::regex_match(t.c_str(), m, family)) return std::nullopt;
  const std::string name = m[1].str();
  if (name != "sph" && name != "exp" && name != "gau" && name != "mat" && name != "wen") {
    if (name == "nug" || name == "pow" || name == "lin")
      throw ArgumentError("--model '" + t + "': fit estimates bounded families (sph, exp, gau, mat, wen); " + name +
                          " needs its numbers given, e.g. \"" + name + "(sill=...)\"");
    return std::nullopt;  // not a family name: the model reader says what is wrong
  }
  FieldModelFamily f;
  f.kind = model_kind_from_name(name);
  if (m[2].matched) {
    const std::string v = m[3].str();
    if (f.kind != ModelKind::Matern)
      throw ArgumentError("--model '" + t + "': only mat takes a smoothness, e.g. mat(2.5)");
    char* end = nullptr;
    const double nu = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !(nu > 0.0 && nu <= 100.0))
      throw ArgumentError("--model '" + t + "': the Matérn smoothness '" + v + "' must be a number in (0, 100]");
    f.nu = nu;
  }
  if (m[6].matched) f.ard = m[6].str() == "ard";
  return f;
}

}  // namespace errfield::compensation
