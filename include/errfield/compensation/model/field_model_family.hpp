#pragma once
/// A variogram family whose parameters `errfield fit` estimates: `--model mat` (or sph, exp, gau,
/// wen; `mat(2.5)` fixes the Matérn smoothness; a suffix `@iso` or `@ard` fixes the anisotropy in
/// joint space) instead of a model with every number given (`--model "gau(sill=..,range=..)"`) or
/// the automatic choice (`--model auto`). The nugget is always estimated with it. In joint space
/// the REML fit of `fit`'s default is restricted to the family; in task space the weighted fit to
/// the empirical variogram is.

#include <optional>
#include <string>
#include <string_view>

#include "errfield/variogram_model.hpp"

namespace errfield::compensation {

struct FieldModelFamily {
  ModelKind kind = ModelKind::Gaussian;
  std::optional<double> nu;    ///< mat only; empty = 1.5 and 2.5 both tried
  std::optional<bool> ard;     ///< joint space: true = ARD only, false = isotropic only, empty = both
  std::string to_string() const;
};

/// The family a `--model` text names, or nothing when the text is not a bare family (a full model
/// text or a file: VariogramModel's reader takes it). Throws ArgumentError for a family errfield
/// cannot estimate (nug, pow, lin) or a bad nu/suffix, naming the text.
std::optional<FieldModelFamily> parse_field_model_family(std::string_view text);

}  // namespace errfield::compensation
