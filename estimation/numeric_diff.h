// A central-difference Ceres cost function that survives a probe outside the model's domain: where
// one side of a difference has no value (a muscle without a steady state there), that column falls
// back to the one-sided difference instead of failing the whole solve. Where both sides have a value
// it is Ceres's own DynamicNumericDiffCostFunction<CENTRAL> (the same steps, the same numbers).
#pragma once

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace armsim {

/// Functor: bool operator()(double const* const* x, double* residuals) const, one parameter block.
template <class Functor>
class SteppingNumericDiffCost final : public ceres::CostFunction {
public:
    /// Takes ownership of `functor`.
    SteppingNumericDiffCost(Functor* functor, int numParameters, int numResiduals)
        : functor_(functor),
          central_(functor, ceres::DO_NOT_TAKE_OWNERSHIP) {
        central_.AddParameterBlock(numParameters);
        central_.SetNumResiduals(numResiduals);
        mutable_parameter_block_sizes()->push_back(numParameters);
        set_num_residuals(numResiduals);
    }

    bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
        if (central_.Evaluate(parameters, residuals, jacobians)) return true;
        if (jacobians == nullptr || jacobians[0] == nullptr) return false;   // no value at x itself
        if (!(*functor_)(parameters, residuals)) return false;
        const int n = parameter_block_sizes()[0], m = num_residuals();
        std::vector<double> x(parameters[0], parameters[0] + n);
        std::vector<double> plus(static_cast<std::size_t>(m)), minus(static_cast<std::size_t>(m));
        const double* probe[1] = {x.data()};
        const double minStep = std::sqrt(std::numeric_limits<double>::epsilon());   // as Ceres
        for (int j = 0; j < n; ++j) {
            const double xj = x[std::size_t(j)];
            const double delta = std::max(minStep, std::abs(xj) * kRelativeStep);
            x[std::size_t(j)] = xj + delta;
            const bool up = (*functor_)(probe, plus.data());
            x[std::size_t(j)] = xj - delta;
            const bool down = (*functor_)(probe, minus.data());
            x[std::size_t(j)] = xj;
            for (int i = 0; i < m; ++i) {
                double& d = jacobians[0][std::size_t(i) * std::size_t(n) + std::size_t(j)];
                if (up && down) d = (plus[std::size_t(i)] - minus[std::size_t(i)]) / (2 * delta);
                else if (up) d = (plus[std::size_t(i)] - residuals[i]) / delta;
                else if (down) d = (residuals[i] - minus[std::size_t(i)]) / delta;
                else return false;
            }
        }
        return true;
    }

private:
    static constexpr double kRelativeStep = 1e-6;   // ceres::NumericDiffOptions::relative_step_size
    std::unique_ptr<Functor> functor_;
    ceres::DynamicNumericDiffCostFunction<Functor, ceres::CENTRAL> central_;
};

}  // namespace armsim
