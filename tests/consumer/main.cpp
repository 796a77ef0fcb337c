// Uses a public header and a compiled function of the installed library; prints a model value.
#include <cstdio>

#include <errfield/variogram_model.hpp>

int main() {
  const auto model = errfield::VariogramModel::parse("sph(sill=2,range=100)");
  std::printf("%.6f\n", model.gamma(100.0));
  return model.gamma(100.0) == 2.0 ? 0 : 1;
}
