#pragma once
// The correlation functions of the likelihood's gradient path with their derivative, shared by the
// exact profile (likelihood_profile.cpp) and the Vecchia approximation (likelihood_vecchia.cpp).

#include <cmath>

#include "errfield/variogram_model.hpp"

namespace errfield::detail {

// Correlation rho(r) at the scaled lag r = h / a and rho'(r) / r, which stays finite at r -> 0 for
// every kind here except exp (where it multiplies a squared coordinate lag <= r^2, so the product
// is finite; at r = 0 the pair is a duplicate and contributes nothing).
struct Correlation {
  ModelKind kind;
  int matern = 0;  // 1, 3, 5: nu = 0.5, 1.5, 2.5
  void operator()(double r, double& rho, double& d) const {
    switch (kind) {
      case ModelKind::Spherical:
        if (r >= 1.0) {
          rho = 0.0, d = 0.0;
        } else {
          rho = 1.0 - r * (1.5 - 0.5 * r * r);
          d = r > 0.0 ? 1.5 * (r * r - 1.0) / r : 0.0;
        }
        return;
      case ModelKind::Gaussian: {
        rho = std::exp(-r * r);
        d = -2.0 * rho;
        return;
      }
      case ModelKind::Wendland:
        if (r >= 1.0) {
          rho = 0.0, d = 0.0;
        } else {
          const double s = 1.0 - r;
          rho = s * s * s * s * (4.0 * r + 1.0);
          d = -20.0 * s * s * s;
        }
        return;
      default: {
        const double e = std::exp(-r);
        if (matern == 1) {
          rho = e;
          d = r > 0.0 ? -e / r : 0.0;
        } else if (matern == 3) {
          rho = (1.0 + r) * e;
          d = -e;
        } else {
          rho = (1.0 + r + r * r / 3.0) * e;
          d = -(1.0 + r) * e / 3.0;
        }
      }
    }
  }
};

inline Correlation correlation_of(const ModelComponent& c) {
  Correlation k{c.kind};
  if (c.kind == ModelKind::Exponential) k.matern = 1;
  if (c.kind == ModelKind::Matern) k.matern = c.nu == 0.5 ? 1 : c.nu == 1.5 ? 3 : 5;
  return k;
}

}  // namespace errfield::detail
