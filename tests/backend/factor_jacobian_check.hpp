#pragma once
/// \file
/// Checking an engine factor's analytic Jacobians (least_squares.hpp: d r / d delta in each
/// variable's tangent space) against central differences through the variables' manifolds.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "cairn/backend/least_squares.hpp"

namespace cairn::backend::test {

/// Max |analytic - numeric| / (1 + |numeric|) over every Jacobian entry of `factor` at `values`,
/// numeric by central differences x [+] (+-h e_k) through each variable's manifold.
inline double jacobian_error(const Factor& factor, std::vector<std::vector<double>> values,
                             const std::vector<const Manifold*>& manifolds) {
  const int m = factor.residual_size();
  const std::size_t n = values.size();
  std::vector<const double*> pointers(n);
  for (std::size_t k = 0; k < n; ++k) pointers[k] = values[k].data();
  std::vector<std::vector<double>> analytic(n);
  std::vector<double*> jacobians(n);
  for (std::size_t k = 0; k < n; ++k) {
    analytic[k].assign(static_cast<std::size_t>(m * manifolds[k]->tangent_size()), 0.0);
    jacobians[k] = analytic[k].data();
  }
  std::vector<double> residual(m), residual_only(m);
  EXPECT_TRUE(factor.evaluate(pointers.data(), residual.data(), jacobians.data()));
  // The residual is the same with and without Jacobians.
  EXPECT_TRUE(factor.evaluate(pointers.data(), residual_only.data(), nullptr));
  for (int i = 0; i < m; ++i) EXPECT_NEAR(residual[i], residual_only[i], 1e-12 * (1.0 + std::abs(residual[i])));
  double worst = 0.0;
  const double h = 1e-6;
  for (std::size_t k = 0; k < n; ++k) {
    const int t = manifolds[k]->tangent_size();
    const std::vector<double> original = values[k];
    for (int j = 0; j < t; ++j) {
      std::vector<double> delta(t, 0.0), plus(m), minus(m);
      delta[j] = h;
      manifolds[k]->plus(original.data(), delta.data(), values[k].data());
      EXPECT_TRUE(factor.evaluate(pointers.data(), plus.data(), nullptr));
      delta[j] = -h;
      manifolds[k]->plus(original.data(), delta.data(), values[k].data());
      EXPECT_TRUE(factor.evaluate(pointers.data(), minus.data(), nullptr));
      values[k] = original;
      for (int i = 0; i < m; ++i) {
        const double numeric = (plus[i] - minus[i]) / (2.0 * h);
        worst = std::max(worst, std::abs(analytic[k][i * t + j] - numeric) / (1.0 + std::abs(numeric)));
      }
    }
  }
  return worst;
}

}  // namespace cairn::backend::test
