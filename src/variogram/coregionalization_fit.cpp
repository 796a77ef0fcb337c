// Fitting the coregionalization matrices of an LMC: gstat's fit.lmc and Goulard-Voltz (see
// coregionalization_fit.hpp for the objective and the methods).

#include "errfield/coregionalization_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "errfield/csv_table.hpp"
#include "errfield/error.hpp"
#include "errfield/variogram_fit.hpp"

namespace errfield {

std::string_view lmc_fit_method_name(LmcFitMethod m) {
  return m == LmcFitMethod::Gstat ? "gstat" : "goulard-voltz";
}

LmcFitMethod lmc_fit_method_from_name(std::string_view name) {
  if (name == "goulard-voltz") return LmcFitMethod::GoulardVoltz;
  if (name == "gstat") return LmcFitMethod::Gstat;
  throw ArgumentError("LMC fit method '" + std::string(name) + "'; expected goulard-voltz or gstat");
}

std::string_view lmc_weighting_name(LmcWeighting w) {
  switch (w) {
    case LmcWeighting::Nj: return "nj";
    case LmcWeighting::Unweighted: return "unweighted";
    case LmcWeighting::NjOverH2: break;
  }
  return "nj_h2";
}

LmcWeighting lmc_weighting_from_name(std::string_view name) {
  if (name == "nj" || name == "1") return LmcWeighting::Nj;
  if (name == "nj_h2" || name == "7") return LmcWeighting::NjOverH2;
  if (name == "unweighted" || name == "6") return LmcWeighting::Unweighted;
  throw ArgumentError("LMC fit weights '" + std::string(name) +
                      "'; expected nj (gstat fit.method 1), nj_h2 (7) or unweighted (6)");
}

void CoregionalizationFitOptions::validate() const {
  if (!(relative_tolerance > 0.0 && relative_tolerance < 1.0))
    throw ArgumentError("LMC fit options: relative_tolerance = " + std::to_string(relative_tolerance) +
                        "; expected 0 < relative_tolerance < 1");
  if (max_iterations < 1)
    throw ArgumentError("LMC fit options: max_iterations = " + std::to_string(max_iterations) + "; expected >= 1");
}

CrossVariogramTable CrossVariogramTable::from(const EmpiricalVariogram& v) {
  const int P = v.components();
  if (P >= 2 && v.cross_gamma.cols() != P * (P - 1) / 2)
    throw ArgumentError("cross-variogram table: the empirical variogram has no cross-variograms; compute it with "
                        "EmpiricalVariogramOptions::cross_variograms");
  CrossVariogramTable t;
  for (std::size_t b = 0; b < v.bins.size(); ++b) {
    t.lag.push_back(v.bins[b].lag_mean);
    t.pairs.push_back(v.bins[b].pairs);
    Eigen::MatrixXd g(P, P);
    for (int i = 0; i < P; ++i)
      for (int j = 0; j < P; ++j) g(i, j) = v.bins[b].pairs == 0 ? 0.0 : v.gamma_of(b, i, j);
    t.gamma.push_back(std::move(g));
  }
  return t;
}

CrossVariogramTable CrossVariogramTable::from(const HeterotopicVariogram& h) {
  const EmpiricalVariogram& v = h.variogram;
  const int P = v.components();
  if (P >= 2 && (v.cross_gamma.cols() != P * (P - 1) / 2 || h.cross_pairs.cols() != P * (P - 1) / 2))
    throw ArgumentError("cross-variogram table: the heterotopic variogram has no cross-variograms; compute it with "
                        "EmpiricalVariogramOptions::cross_variograms");
  CrossVariogramTable t;
  const auto bins = static_cast<Eigen::Index>(v.bins.size());
  for (Eigen::Index b = 0; b < bins; ++b) {
    t.lag.push_back(v.bins[static_cast<std::size_t>(b)].lag_mean);
    t.pairs.push_back(v.bins[static_cast<std::size_t>(b)].pairs);
    Eigen::MatrixXd g(P, P), lag(P, P), pairs(P, P);
    for (int i = 0; i < P; ++i)
      for (int l = i; l < P; ++l) {
        const bool direct = i == l;
        const int c = direct ? i : EmpiricalVariogram::cross_column(i, l, P);
        g(i, l) = g(l, i) = direct ? v.component_gamma(b, c) : v.cross_gamma(b, c);
        lag(i, l) = lag(l, i) = direct ? h.component_lag(b, c) : h.cross_lag(b, c);
        pairs(i, l) = pairs(l, i) = direct ? h.component_pairs(b, c) : h.cross_pairs(b, c);
      }
    t.gamma.push_back(std::move(g));
    t.entry_lag.push_back(std::move(lag));
    t.entry_pairs.push_back(std::move(pairs));
  }
  return t;
}

namespace {

/// The usable bins of a table: lag, weight and gamma matrix.
struct LmcBins {
  std::vector<double> lag, weight;
  std::vector<std::uint64_t> pairs;
  std::vector<Eigen::MatrixXd> gamma;
  int components = 0;
};

LmcBins usable_bins(const CrossVariogramTable& t, LmcWeighting weighting) {
  if (t.lag.size() != t.pairs.size() || t.lag.size() != t.gamma.size())
    throw ArgumentError("cross-variogram table: " + std::to_string(t.lag.size()) + " lags, " +
                        std::to_string(t.pairs.size()) + " pair counts and " + std::to_string(t.gamma.size()) +
                        " gamma matrices; expected one of each per bin");
  LmcBins b;
  b.components = t.gamma.empty() ? 0 : static_cast<int>(t.gamma.front().rows());
  if (b.components < 2)
    throw ArgumentError("LMC fit: " + std::to_string(b.components) +
                        " component(s); an LMC fit needs at least 2 (with 1, use fit_variogram)");
  for (std::size_t j = 0; j < t.lag.size(); ++j) {
    const Eigen::MatrixXd& g = t.gamma[j];
    if (g.rows() != b.components || g.cols() != b.components)
      throw ArgumentError("cross-variogram table: bin " + std::to_string(j) + " has a " + std::to_string(g.rows()) +
                          " x " + std::to_string(g.cols()) + " gamma matrix; expected " +
                          std::to_string(b.components) + " x " + std::to_string(b.components));
    if (t.pairs[j] == 0) continue;
    if (!std::isfinite(t.lag[j]) || t.lag[j] < 0.0)
      throw InputError("cross-variogram table: bin " + std::to_string(j) + " has lag " + std::to_string(t.lag[j]) +
                       "; expected a finite lag >= 0");
    if (!g.allFinite())
      throw InputError("cross-variogram table: bin " + std::to_string(j) + " has a non-finite gamma");
    const double scale = std::max(g.cwiseAbs().maxCoeff(), 1e-300);
    if (((g - g.transpose()).cwiseAbs().array() > 1e-12 * scale).any())
      throw InputError("cross-variogram table: bin " + std::to_string(j) + " has an asymmetric gamma matrix");
    // gstat's fit.method 7 refuses lag 0; a bin of coincident points carries no range information.
    if (weighting == LmcWeighting::NjOverH2 && t.lag[j] == 0.0) continue;
    const double n = static_cast<double>(t.pairs[j]);
    b.lag.push_back(t.lag[j]);
    b.pairs.push_back(t.pairs[j]);
    b.weight.push_back(weighting == LmcWeighting::Nj         ? n
                       : weighting == LmcWeighting::NjOverH2 ? n / (t.lag[j] * t.lag[j])
                                                             : 1.0);
    b.gamma.push_back(g);
  }
  return b;
}

/// A component whose direct variogram is 0 in every used bin (constant values) has no spatial
/// variation to fit: its LMC row would be all zeros, a model that predicts nothing and reads as a
/// fit (written with exit 0). Refused, naming the component(s). `names` may be empty.
void check_spatial_variation(const LmcBins& b, const std::vector<std::string>& names) {
  std::string flat;
  int count = 0;
  for (int i = 0; i < b.components; ++i) {
    bool zero = true;
    for (const Eigen::MatrixXd& g : b.gamma) zero = zero && g(i, i) == 0.0;
    if (!zero) continue;
    ++count;
    const auto k = static_cast<std::size_t>(i);
    flat += std::string(flat.empty() ? "" : ", ") +
            (k < names.size() ? "'" + names[k] + "'" : "component " + std::to_string(i + 1));
  }
  if (count == 0 || b.gamma.empty()) return;
  throw InputError("LMC fit: no spatial variation in " + flat + ": the direct variogram is 0 in all " +
                   std::to_string(b.gamma.size()) + " bins (constant values" +
                   (count == b.components ? ", every component" : "") +
                   "); an LMC of it is all zeros and predicts nothing: drop " + (count == 1 ? "it" : "them") +
                   " or check the data");
}

void check_structures(const std::vector<ModelComponent>& structures) {
  if (structures.empty()) throw ArgumentError("LMC fit: no structures; expected e.g. nug(0)+sph(1,400)");
  for (std::size_t k = 0; k < structures.size(); ++k) {
    const ModelComponent& s = structures[k];
    if (!s.bounded())
      throw ArgumentError("LMC fit: structure " + std::to_string(k) + " is " + std::string(model_kind_name(s.kind)) +
                          ", which has no sill; an LMC needs bounded structures (nug, sph, exp, gau, mat, wen)");
  }
}

/// Design matrix X(j, k) = g_k(h_j) with unit sills, at the lags h.
Eigen::MatrixXd unit_design(const std::vector<double>& lag, const std::vector<ModelComponent>& structures) {
  Eigen::MatrixXd x(static_cast<Eigen::Index>(lag.size()), static_cast<Eigen::Index>(structures.size()));
  for (std::size_t k = 0; k < structures.size(); ++k) {
    ModelComponent unit = structures[k];
    unit.sill = 1.0;
    for (std::size_t j = 0; j < lag.size(); ++j) x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k)) = unit.gamma(lag[j]);
  }
  return x;
}

/// Linear WLS of y on the columns of x marked free (the others fixed at 0).
Eigen::VectorXd weighted_linear_fit(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& sw,
                                    const std::vector<bool>& free) {
  std::vector<Eigen::Index> cols;
  for (Eigen::Index k = 0; k < x.cols(); ++k)
    if (free[static_cast<std::size_t>(k)]) cols.push_back(k);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(x.cols());
  if (cols.empty()) return b;
  Eigen::MatrixXd a(x.rows(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) a.col(static_cast<Eigen::Index>(c)) = x.col(cols[c]).cwiseProduct(sw);
  const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(y.cwiseProduct(sw));
  for (std::size_t c = 0; c < cols.size(); ++c) b(cols[c]) = coef(static_cast<Eigen::Index>(c));
  return b;
}

/// The partial sills of one direct or cross variogram by WLS on the unit design; a direct one's
/// (`direct`) kept non-negative as gstat's fit.variogram does (fit.sills: a negative psill is set to
/// 0 and the rest refitted, until none is negative).
Eigen::VectorXd sills_fit(const Eigen::MatrixXd& x, const Eigen::VectorXd& y, const Eigen::VectorXd& sw, bool direct) {
  std::vector<bool> free(static_cast<std::size_t>(x.cols()), true);
  Eigen::VectorXd coef = weighted_linear_fit(x, y, sw, free);
  while (direct && (coef.array() < 0.0).any()) {
    for (std::size_t k = 0; k < free.size(); ++k) free[k] = free[k] && coef(static_cast<Eigen::Index>(k)) > 0.0;
    coef = weighted_linear_fit(x, y, sw, free);
  }
  return coef;
}

/// Nearest PSD matrix (Frobenius): eigenvalues clipped at 0; also returns the smallest eigenvalue.
Eigen::MatrixXd psd_projection(const Eigen::MatrixXd& m, double& smallest) {
  const Eigen::MatrixXd sym = 0.5 * (m + m.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sym);
  smallest = eig.eigenvalues().minCoeff();
  if (smallest >= 0.0) return sym;
  const Eigen::VectorXd d = eig.eigenvalues().cwiseMax(0.0);
  Eigen::MatrixXd p = eig.eigenvectors() * d.asDiagonal() * eig.eigenvectors().transpose();
  return 0.5 * (p + p.transpose());
}

double lmc_residual(const LmcBins& b, const Eigen::MatrixXd& x, const std::vector<Eigen::MatrixXd>& sills) {
  double q = 0.0;
  for (std::size_t j = 0; j < b.lag.size(); ++j) {
    Eigen::MatrixXd r = b.gamma[j];
    for (std::size_t k = 0; k < sills.size(); ++k)
      r -= x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k)) * sills[k];
    q += b.weight[j] * r.squaredNorm();
  }
  return q;
}

/// gstat's fit.lmc: per direct/cross variogram a linear WLS of the partial sills; a direct
/// variogram's negative sills are fixed at 0 and the others refitted (fit.variogram's rule for
/// direct variograms), until none is negative. Unprojected.
std::vector<Eigen::MatrixXd> separate_fits(const LmcBins& b, const Eigen::MatrixXd& x) {
  const int P = b.components;
  const std::size_t K = static_cast<std::size_t>(x.cols());
  std::vector<Eigen::MatrixXd> sills(K, Eigen::MatrixXd::Zero(P, P));
  const Eigen::VectorXd sw = Eigen::Map<const Eigen::VectorXd>(b.weight.data(), static_cast<Eigen::Index>(b.weight.size())).cwiseSqrt();
  Eigen::VectorXd y(x.rows());
  for (int i = 0; i < P; ++i) {
    for (int l = i; l < P; ++l) {
      for (std::size_t j = 0; j < b.lag.size(); ++j) y(static_cast<Eigen::Index>(j)) = b.gamma[j](i, l);
      const Eigen::VectorXd coef = sills_fit(x, y, sw, i == l);
      for (std::size_t k = 0; k < K; ++k) sills[k](i, l) = sills[k](l, i) = coef(static_cast<Eigen::Index>(k));
    }
  }
  return sills;
}

double bin_weight(LmcWeighting weighting, double n, double lag) {
  return weighting == LmcWeighting::Nj ? n : weighting == LmcWeighting::NjOverH2 ? n / (lag * lag) : 1.0;
}

/// One direct or cross variogram of a heterotopic table: its usable bins (pairs > 0; lag > 0 for
/// nj_h2, as for homotopic tables), their lags, weights and gammas.
struct EntryBins {
  std::vector<double> lag, weight, gamma;
};

/// Every entry (i <= l) of a heterotopic table, validated: entries[i * P + l].
std::vector<EntryBins> heterotopic_entries(const CrossVariogramTable& t, LmcWeighting weighting, int& components) {
  if (t.entry_lag.size() != t.gamma.size() || t.entry_pairs.size() != t.gamma.size())
    throw ArgumentError("cross-variogram table: " + std::to_string(t.entry_lag.size()) + " lag matrices, " +
                        std::to_string(t.entry_pairs.size()) + " pair-count matrices and " +
                        std::to_string(t.gamma.size()) + " gamma matrices; expected one of each per bin");
  const int P = t.gamma.empty() ? 0 : static_cast<int>(t.gamma.front().rows());
  components = P;
  if (P < 2)
    throw ArgumentError("LMC fit: " + std::to_string(P) + " component(s); an LMC fit needs at least 2 (with 1, use fit_variogram)");
  std::vector<EntryBins> entries(static_cast<std::size_t>(P * P));
  for (std::size_t j = 0; j < t.gamma.size(); ++j) {
    const Eigen::MatrixXd &g = t.gamma[j], &h = t.entry_lag[j], &n = t.entry_pairs[j];
    for (const Eigen::MatrixXd* m : {&g, &h, &n})
      if (m->rows() != P || m->cols() != P)
        throw ArgumentError("cross-variogram table: bin " + std::to_string(j) + " has a " + std::to_string(m->rows()) + " x " +
                            std::to_string(m->cols()) + " matrix; expected " + std::to_string(P) + " x " + std::to_string(P));
    for (int i = 0; i < P; ++i)
      for (int l = i; l < P; ++l) {
        const double pairs = n(i, l);
        if (!(pairs >= 0.0) || pairs != std::floor(pairs) || n(l, i) != pairs)
          throw InputError("cross-variogram table: bin " + std::to_string(j) + ", entry (" + std::to_string(i) + ", " +
                           std::to_string(l) + "): pair count " + std::to_string(pairs) + "; expected a symmetric integer >= 0");
        if (pairs == 0.0) continue;
        if (!std::isfinite(h(i, l)) || h(i, l) < 0.0)
          throw InputError("cross-variogram table: bin " + std::to_string(j) + ", entry (" + std::to_string(i) + ", " +
                           std::to_string(l) + ") has lag " + std::to_string(h(i, l)) + "; expected a finite lag >= 0");
        if (!std::isfinite(g(i, l)) || g(l, i) != g(i, l))
          throw InputError("cross-variogram table: bin " + std::to_string(j) + ", entry (" + std::to_string(i) + ", " +
                           std::to_string(l) + ") has a non-finite or asymmetric gamma");
        if (weighting == LmcWeighting::NjOverH2 && h(i, l) == 0.0) continue;
        EntryBins& e = entries[static_cast<std::size_t>(i * P + l)];
        e.lag.push_back(h(i, l));
        e.weight.push_back(bin_weight(weighting, pairs, h(i, l)));
        e.gamma.push_back(g(i, l));
      }
  }
  return entries;
}

std::string entry_name(int i, int l, const std::vector<std::string>& names) {
  auto name = [&](int c) {
    const auto k = static_cast<std::size_t>(c);
    return k < names.size() ? "'" + names[k] + "'" : "component " + std::to_string(c + 1);
  };
  return i == l ? "the direct variogram of " + name(i) : "the cross-variogram of " + name(i) + " and " + name(l);
}

/// Q(B) of a heterotopic table: each entry over its own bins and weights (off-diagonal entries
/// twice, as the Frobenius norm of the homotopic Q counts them).
double heterotopic_residual(const std::vector<EntryBins>& entries, int P, const std::vector<ModelComponent>& structures,
                            const std::vector<Eigen::MatrixXd>& sills) {
  double q = 0.0;
  for (int i = 0; i < P; ++i)
    for (int l = i; l < P; ++l) {
      const EntryBins& e = entries[static_cast<std::size_t>(i * P + l)];
      const Eigen::MatrixXd x = unit_design(e.lag, structures);
      for (std::size_t j = 0; j < e.lag.size(); ++j) {
        double r = e.gamma[j];
        for (std::size_t k = 0; k < sills.size(); ++k) r -= x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k)) * sills[k](i, l);
        q += (i == l ? 1.0 : 2.0) * e.weight[j] * r * r;
      }
    }
  return q;
}

/// gstat's fit.lmc on a heterotopic table: each direct and cross variogram fitted alone over its
/// own bins (separate_fits' rules), then each B_k projected onto the PSD cone.
CoregionalizationFitResult fit_heterotopic(const CrossVariogramTable& table, const std::vector<ModelComponent>& structures,
                                           const CoregionalizationFitOptions& options,
                                           std::vector<std::string> component_names) {
  if (options.method != LmcFitMethod::Gstat)
    throw ArgumentError("LMC fit: heterotopic variograms (each over its own pairs and lags) are fitted by the gstat "
                        "method (gstat's fit.lmc: each variogram alone, then the PSD projection); Goulard-Voltz's "
                        "update is exact only when every variogram of a bin has the same weight");
  int P = 0;
  const std::vector<EntryBins> entries = heterotopic_entries(table, options.weighting, P);
  const std::size_t K = structures.size();
  std::vector<Eigen::MatrixXd> sills(K, Eigen::MatrixXd::Zero(P, P));
  std::size_t bins_used = 0;
  for (int i = 0; i < P; ++i)
    for (int l = i; l < P; ++l) {
      const EntryBins& e = entries[static_cast<std::size_t>(i * P + l)];
      if (e.lag.size() < K)
        throw ArgumentError("LMC fit: " + entry_name(i, l, component_names) + " has " + std::to_string(e.lag.size()) +
                            " usable bin(s) for " + std::to_string(K) + " structures; expected at least as many bins " +
                            "as structures" + (i == l ? "" : " (a cross-variogram's pairs are those where both are measured at both ends)"));
      if (i == l && std::all_of(e.gamma.begin(), e.gamma.end(), [](double g) { return g == 0.0; }))
        throw InputError("LMC fit: no spatial variation in " + entry_name(i, l, component_names) +
                         ": it is 0 in all its bins (constant values); an LMC of it predicts nothing: drop it or check the data");
      bins_used = std::max(bins_used, e.lag.size());
      const Eigen::MatrixXd x = unit_design(e.lag, structures);
      const Eigen::VectorXd sw = Eigen::Map<const Eigen::VectorXd>(e.weight.data(), static_cast<Eigen::Index>(e.weight.size())).cwiseSqrt();
      const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(e.gamma.data(), static_cast<Eigen::Index>(e.gamma.size()));
      const Eigen::VectorXd coef = sills_fit(x, y, sw, i == l);
      for (std::size_t k = 0; k < K; ++k) sills[k](i, l) = sills[k](l, i) = coef(static_cast<Eigen::Index>(k));
    }
  CoregionalizationFitResult result;
  result.bins_used = bins_used;
  result.smallest_eigenvalue_before_projection.assign(K, 0.0);
  for (std::size_t k = 0; k < K; ++k) sills[k] = psd_projection(sills[k], result.smallest_eigenvalue_before_projection[k]);
  result.weighted_residual = heterotopic_residual(entries, P, structures, sills);
  result.message = "gstat fit.lmc of heterotopic variograms: each over its own bins, then eigenvalues clipped at 0";
  std::vector<CoregionalizationStructure> out;
  for (std::size_t k = 0; k < K; ++k)
    out.push_back({.kind = structures[k].kind, .range = structures[k].range, .nu = structures[k].nu, .sills = sills[k]});
  result.model = CoregionalizationModel(std::move(out), {}, std::move(component_names));
  return result;
}

}  // namespace

CoregionalizationFitResult fit_coregionalization(const CrossVariogramTable& table,
                                                 const std::vector<ModelComponent>& structures,
                                                 const CoregionalizationFitOptions& options,
                                                 std::vector<std::string> component_names) {
  options.validate();
  check_structures(structures);
  if (table.heterotopic()) return fit_heterotopic(table, structures, options, std::move(component_names));
  const LmcBins b = usable_bins(table, options.weighting);
  check_spatial_variation(b, component_names);
  const std::size_t K = structures.size();
  if (b.lag.size() < K)
    throw ArgumentError("LMC fit: " + std::to_string(b.lag.size()) + " usable bin(s) for " + std::to_string(K) +
                        " structures; expected at least as many bins as structures");
  const Eigen::MatrixXd x = unit_design(b.lag, structures);
  CoregionalizationFitResult result;
  result.bins_used = b.lag.size();
  result.smallest_eigenvalue_before_projection.assign(K, 0.0);
  std::vector<Eigen::MatrixXd> sills = separate_fits(b, x);
  for (std::size_t k = 0; k < K; ++k) sills[k] = psd_projection(sills[k], result.smallest_eigenvalue_before_projection[k]);
  double q = lmc_residual(b, x, sills);
  if (options.method == LmcFitMethod::GoulardVoltz) {
    // Block coordinate descent: with the others fixed, Q(B_k) = c_k ||B_k - U_k||_F^2 + const,
    // c_k = sum_j w_j g_k(h_j)^2 and U_k the unconstrained update, so the PSD projection of U_k is
    // B_k's exact constrained minimizer and Q never increases.
    std::vector<double> c(K, 0.0);
    for (std::size_t k = 0; k < K; ++k)
      for (std::size_t j = 0; j < b.lag.size(); ++j) {
        const double g = x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k));
        c[k] += b.weight[j] * g * g;
      }
    result.converged = false;
    std::vector<Eigen::MatrixXd> fitted(b.lag.size());  // sum_k B_k g_k(h_j)
    while (result.iterations < options.max_iterations) {
      ++result.iterations;
      const std::vector<Eigen::MatrixXd> before = sills;
      // Recomputed every sweep (updated in place within it), so rounding does not accumulate.
      for (std::size_t j = 0; j < b.lag.size(); ++j) {
        fitted[j] = Eigen::MatrixXd::Zero(b.components, b.components);
        for (std::size_t k = 0; k < K; ++k) fitted[j] += x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k)) * sills[k];
      }
      double change = 0.0, size = 0.0;
      for (std::size_t k = 0; k < K; ++k) {
        if (!(c[k] > 0.0)) continue;  // g_k = 0 at every lag: B_k does not enter Q
        Eigen::MatrixXd u = Eigen::MatrixXd::Zero(b.components, b.components);
        for (std::size_t j = 0; j < b.lag.size(); ++j) {
          const double g = x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k));
          u += (b.weight[j] * g) * (b.gamma[j] - fitted[j] + g * sills[k]);
        }
        u /= c[k];
        const Eigen::MatrixXd next = psd_projection(u, result.smallest_eigenvalue_before_projection[k]);
        change = std::max(change, (next - sills[k]).cwiseAbs().maxCoeff());
        size = std::max(size, next.cwiseAbs().maxCoeff());
        for (std::size_t j = 0; j < b.lag.size(); ++j)
          fitted[j] += x(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k)) * (next - sills[k]);
        sills[k] = next;
      }
      const double q_next = lmc_residual(b, x, sills);
      // Converged when no entry of any B_k moved by more than the tolerance relative to the
      // largest entry, or when a sweep no longer lowers Q at all (rounding). A relative test on Q
      // alone would stop early: Q is quadratic in B, so a change of 1e-12 in Q allows 1e-6 in B.
      const bool small_step = change <= options.relative_tolerance * size;
      const bool stalled = q_next >= q;
      if (q_next > q) sills = before;  // a sweep that rounding made worse is undone: Q never rises
      else q = q_next;
      if (small_step || stalled) {
        result.converged = true;
        break;
      }
    }
    result.message = std::string(result.converged ? "converged" : "stopped at max_iterations") + " after " +
                     std::to_string(result.iterations) + " Goulard-Voltz sweep(s)";
  } else {
    result.message = "gstat fit.lmc: separate linear fits, then eigenvalues clipped at 0";
  }
  result.weighted_residual = q;
  std::vector<CoregionalizationStructure> out;
  for (std::size_t k = 0; k < K; ++k)
    out.push_back({.kind = structures[k].kind, .range = structures[k].range, .nu = structures[k].nu, .sills = sills[k]});
  result.model = CoregionalizationModel(std::move(out), {}, std::move(component_names));
  return result;
}

std::vector<ModelComponent> fit_coregionalization_ranges(const CrossVariogramTable& table,
                                                         const std::vector<ModelComponent>& structures,
                                                         LmcWeighting weighting,
                                                         const std::vector<std::string>& component_names) {
  check_structures(structures);
  if (table.heterotopic())
    throw ArgumentError("LMC fit: heterotopic variograms (each over its own pairs and lags): give the structures' "
                        "ranges (e.g. nug(0)+sph(1,40)), as gstat's fit.lmc takes them from the model");
  const LmcBins b = usable_bins(table, weighting);
  check_spatial_variation(b, component_names);
  std::vector<ModelComponent> ranged;
  bool nugget = false;
  for (const ModelComponent& s : structures) {
    if (s.kind == ModelKind::Nugget) nugget = true;
    else ranged.push_back(s);
  }
  if (ranged.empty()) return structures;
  std::vector<double> mean;
  std::vector<std::uint64_t> n;
  for (std::size_t j = 0; j < b.lag.size(); ++j) {
    mean.push_back(b.gamma[j].trace() / b.components);
    // fit_variogram knows N_j and N_j / h_j^2; unweighted is N_j with every N_j = 1.
    n.push_back(weighting == LmcWeighting::Unweighted ? 1 : b.pairs[j]);
  }
  VariogramFitOptions o;
  o.weighting = weighting == LmcWeighting::NjOverH2 ? FitWeighting::NjOverH2 : FitWeighting::Nj;
  o.nugget = nugget ? NuggetMode::Free : NuggetMode::None;
  const VariogramFitResult r = fit_variogram(b.lag, mean, n, ranged, o);
  if (r.status == FitStatus::Failed)
    throw ArgumentError("LMC fit: fitting the ranges to the mean direct variogram failed: " + r.message);
  std::vector<ModelComponent> out = structures;
  std::size_t next = 0;
  for (ModelComponent& s : out)
    if (s.kind != ModelKind::Nugget) s.range = r.model.components()[next++].range;
  return out;
}

CoregionalizationTemplate parse_coregionalization_template(std::string_view text, double nu) {
  const std::string hint = " (an LMC template is a model such as nug(0)+sph(1,400): kinds and ranges kept, sills "
                           "ignored; or kinds such as nug+sph: ranges fitted to the mean direct variogram)";
  CoregionalizationTemplate t;
  if (text.find('(') != std::string_view::npos) {
    VariogramModel m;
    try {
      m = VariogramModel::parse(text);
    } catch (const ArgumentError& e) {
      throw ArgumentError(std::string(e.what()) + hint);
    }
    t.anisotropy = m.anisotropy();
    t.structures = m.components();
    t.ranges_given = true;
  } else {
    std::vector<std::string> kinds{""};
    for (char ch : text) {
      if (ch == '+') kinds.emplace_back();
      else if (ch != ' ') kinds.back() += ch;
    }
    for (const std::string& name : kinds) {
      ModelComponent c;
      try {
        c.kind = model_kind_from_name(name);
      } catch (const ArgumentError& e) {
        throw ArgumentError("LMC template '" + std::string(text) + "': " + e.what() + hint);
      }
      if (c.kind == ModelKind::Matern) {
        if (!(nu > 0.0 && nu <= kMaxMaternNu))
          throw ArgumentError("LMC template '" + std::string(text) + "' has mat: give its smoothness nu, 0 < nu <= " +
                              format_number(kMaxMaternNu) + (nu > 0.0 ? ", got " + format_number(nu) : std::string()));
        c.nu = nu;
      }
      t.structures.push_back(c);
    }
  }
  for (const ModelComponent& c : t.structures)
    if (!c.bounded())
      throw ArgumentError("LMC template '" + std::string(text) + "': " + std::string(model_kind_name(c.kind)) +
                          " has no sill; an LMC needs bounded structures (nug, sph, exp, gau, mat, wen)");
  return t;
}

double coregionalization_weighted_residual(const CrossVariogramTable& table, const CoregionalizationModel& model,
                                           LmcWeighting weighting) {
  std::vector<ModelComponent> structures;
  std::vector<Eigen::MatrixXd> sills;
  for (const CoregionalizationStructure& s : model.structures()) {
    structures.push_back({.kind = s.kind, .sill = 1.0, .range = s.range, .nu = s.nu});
    sills.push_back(s.sills);
  }
  if (table.heterotopic()) {
    int P = 0;
    return heterotopic_residual(heterotopic_entries(table, weighting, P), P, structures, sills);
  }
  const LmcBins b = usable_bins(table, weighting);
  return lmc_residual(b, unit_design(b.lag, structures), sills);
}

}  // namespace errfield
