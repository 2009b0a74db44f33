// The direct stiff integrator (CPodes without a Simbody System): closed-form solutions, restarts at
// breakpoints, sampling, and failures reported with the time and the model's message.
#include "basics/errors.h"
#include "basics/format.h"
#include "numerics/cpodes_c.h"
#include "numerics/stiff_ode.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

using namespace armsim;

namespace {

constexpr double kStiffRate = 1000;  // 1/s: y1 relaxes 2000x faster than y2
constexpr double kSlowRate = 0.5;    // 1/s
constexpr double kStepTime = 0.3;    // s: the input of y2 steps from 0 to 1

// y1' = -k (y1 - sin t), y2' = -c y2 + H(t - t_s).
void calcRhs(double t, const double* y, double* ydot) {
    ydot[0] = -kStiffRate * (y[0] - std::sin(t));
    ydot[1] = -kSlowRate * y[1] + (t >= kStepTime ? 1.0 : 0.0);
}

double exactY1(double t, double y0) {
    const double k = kStiffRate, k2 = k * k;
    const double particular = (k2 * std::sin(t) - k * std::cos(t)) / (k2 + 1);
    return particular + (y0 + k / (k2 + 1)) * std::exp(-k * t);
}

double exactY2(double t, double y0) {
    const double decay = y0 * std::exp(-kSlowRate * t);
    return t < kStepTime ? decay : decay + (1 - std::exp(-kSlowRate * (t - kStepTime))) / kSlowRate;
}

}  // namespace

TEST(StiffOde, StiffLinearSystemMatchesItsClosedFormThroughAStepInput) {
    constexpr double kAbsTol = 2e-5;  // accuracy 1e-6 on states of order 1, global error
    IntegrationSettings settings;
    settings.accuracy = 1e-6;
    std::vector<double> y{1.0, 0.5};
    int samples = 0;
    double worst = 0;
    const IntegrationStats stats = integrateSampled(
        calcRhs, 0.0, y, 2.0, 100.0, {kStepTime}, settings, [&](double t, const double* ys) {
            EXPECT_NEAR(t, samples / 100.0, 1e-12);
            worst = std::max({worst, std::abs(ys[0] - exactY1(t, 1.0)), std::abs(ys[1] - exactY2(t, 0.5))});
            ++samples;
        });
    EXPECT_EQ(samples, 201);
    EXPECT_LE(worst, kAbsTol);
    EXPECT_NEAR(y[0], exactY1(2.0, 1.0), kAbsTol);
    EXPECT_NEAR(y[1], exactY2(2.0, 0.5), kAbsTol);
    EXPECT_EQ(stats.restarts, 1);  // at the step
    // Stiff: an implicit method steps far beyond the explicit stability limit 2 / k = 2 ms.
    EXPECT_LT(stats.steps, 1000 / 2);
    EXPECT_GE(stats.realizations, stats.steps);
}

TEST(StiffOde, ARightHandSideThatThrowsIsReportedWithTheTimeAndTheModelsMessage) {
    std::vector<double> y{1.0};
    const OdeRhs f = [](double t, const double* yi, double* ydot) {
        if (t > 0.25) throw SimulationError("muscle 'X' beyond its range");
        ydot[0] = -yi[0];
    };
    try {
        integrateSampled(f, 0.0, y, 1.0, 10.0, {}, IntegrationSettings{}, [](double, const double*) {});
        ADD_FAILURE() << "no error";
    } catch (const SimulationError& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find("t = 0.2"), std::string::npos) << m;
        EXPECT_NE(m.find("beyond its range"), std::string::npos) << m;
    }
}

TEST(StiffOde, ACheckAtStepBoundariesStopsTheRunAndNonFiniteStatesAreNamed) {
    std::vector<double> y{1.0};
    const OdeRhs grow = [](double, const double* yi, double* ydot) { ydot[0] = yi[0]; };
    auto check = [](double t, const double* yi) {
        if (yi[0] > 2) throw SimulationError("t = " + formatNumber(t) + " s: y left (0, 2]");
    };
    try {
        integrateSampled(grow, 0.0, y, 2.0, 10.0, {}, IntegrationSettings{}, [](double, const double*) {}, check);
        ADD_FAILURE() << "no error";
    } catch (const SimulationError& e) {
        EXPECT_NE(std::string(e.what()).find("left (0, 2]"), std::string::npos) << e.what();
    }
    std::vector<double> bad{std::nan("")};
    EXPECT_THROW(integrateSampled(grow, 0.0, bad, 1.0, 10.0, {}, IntegrationSettings{}, [](double, const double*) {}),
                 SimulationError);
    std::vector<double> ok{1.0};
    EXPECT_THROW(integrateSampled(grow, 0.0, ok, -1.0, 10.0, {}, IntegrationSettings{}, [](double, const double*) {}),
                 InputError);
}

// Issue 14: integrateSampled drives CPODES through its C interface with armsim's own N_Vector; the
// declarations in numerics/cpodes_c.h must match the loaded libSimTKmath (ops table order, serial
// content, dispatch), or every run would corrupt memory.
TEST(StiffOde, TheDeclaredCpodesLayoutMatchesTheLoadedLibrary) {
    EXPECT_EQ(cpodes::findCpodesLayoutMismatch(), "");
}

// Issue 14: a block-structured f (independent blocks, one evaluated per Jacobian column) takes the
// same steps and gives the same samples, bit for bit, as the same f handed over whole.
TEST(StiffOde, BlocksGiveTheSameStepsAndSamplesAsTheWholeRightHandSide) {
    // Three independent blocks: a constant pair, a stiff nonlinear pair with a step input, a scalar.
    auto calcBlock = [](int b, double t, const double* y, double* ydot) {
        if (b == 0) {
            ydot[0] = ydot[1] = 0;
        } else if (b == 1) {
            const double u = t >= kStepTime ? 1.0 : 0.2;
            ydot[2] = -kStiffRate * (y[2] - u * y[3] * y[3]);
            ydot[3] = -kSlowRate * y[3] + std::sin(3 * t) * y[2];
        } else {
            ydot[4] = -std::exp(y[4]) + 1.5;
        }
    };
    OdeBlocks blocks;
    blocks.first = {0, 2, 4};
    blocks.size = {2, 2, 1};
    blocks.calcBlock = calcBlock;
    const OdeRhs whole = [&](double t, const double* y, double* ydot) {
        for (int b = 0; b < 3; ++b) calcBlock(b, t, y, ydot);
    };
    std::vector<std::vector<double>> samplesWhole, samplesBlocks;
    std::vector<double> y1{0.3, 0.0, 0.5, 0.8, -1.0}, y2 = y1;
    const IntegrationStats a = integrateSampled(whole, 0.0, y1, 1.0, 200.0, {kStepTime}, IntegrationSettings{},
                                                [&](double, const double* y) { samplesWhole.emplace_back(y, y + 5); });
    const IntegrationStats b = integrateSampled(blocks, 0.0, y2, 1.0, 200.0, {kStepTime}, IntegrationSettings{},
                                                [&](double, const double* y) { samplesBlocks.emplace_back(y, y + 5); });
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_EQ(a.realizations, b.realizations);
    EXPECT_EQ(a.partialEvaluations, 0);
    EXPECT_GT(b.partialEvaluations, 0);
    EXPECT_EQ(samplesWhole, samplesBlocks);  // exactly
    EXPECT_EQ(y1, y2);

    // Banded (issue 30): Newton's systems as a band of half-width max(size) - 1 = 1. Its own steps, so
    // the samples agree to the integration's accuracy: at 1e-9, within 1e-6 (the tolerance).
    constexpr double kBandTol = 1e-6;
    IntegrationSettings tight;
    tight.accuracy = 1e-9;
    OdeBlocks banded = blocks;
    banded.banded = true;
    std::vector<std::vector<double>> samplesDense, samplesBanded;
    std::vector<double> y3{0.3, 0.0, 0.5, 0.8, -1.0}, y4 = y3;
    integrateSampled(whole, 0.0, y3, 1.0, 200.0, {kStepTime}, tight, [&](double, const double* y) { samplesDense.emplace_back(y, y + 5); });
    integrateSampled(banded, 0.0, y4, 1.0, 200.0, {kStepTime}, tight, [&](double, const double* y) { samplesBanded.emplace_back(y, y + 5); });
    ASSERT_EQ(samplesDense.size(), samplesBanded.size());
    for (std::size_t k = 0; k < samplesDense.size(); ++k)
        for (int i = 0; i < 5; ++i) EXPECT_NEAR(samplesBanded[k][i], samplesDense[k][i], kBandTol) << k << " " << i;

    OdeBlocks overlapping = blocks;
    overlapping.first = {0, 1, 4};
    EXPECT_THROW(integrateSampled(overlapping, 0.0, y2, 1.0, 10.0, {}, IntegrationSettings{}, [](double, const double*) {}),
                 std::invalid_argument);
    OdeBlocks gap = blocks;
    gap.size = {2, 1, 1};
    EXPECT_THROW(integrateSampled(gap, 0.0, y2, 1.0, 10.0, {}, IntegrationSettings{}, [](double, const double*) {}),
                 std::invalid_argument);
}

// OdeArrow (issue 30): a stiff linear system whose Jacobian is an arrow, a damped oscillator [q u]
// driving three two-state blocks that relax to it at 1, 100 and 1000 1/s and pull it back; its
// closed form is exp(A t) y0. The block-and-Schur-complement solve must give it to the accuracy asked.
TEST(StiffOde, AnArrowShapedSystemMatchesItsClosedForm) {
    constexpr double kAbsTol = 1e-6;   // accuracy 1e-8 on states of order 1, global error
    const int nc = 2, nb = 3, n = nc + 2 * nb;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
    A(0, 1) = 1;
    A(1, 0) = -40;   // omega^2
    A(1, 1) = -0.5;
    const double rates[nb] = {1, 100, 1000};
    for (int b = 0; b < nb; ++b) {
        const int i = nc + 2 * b;
        A(i, i) = -rates[b];
        A(i, 0) = rates[b];           // relaxes to q
        A(i + 1, i) = 3;
        A(i + 1, i + 1) = -2 * rates[b];
        A(i + 1, 1) = 0.5;            // and feels u
        A(1, i) = 2.0 * (b + 1);      // pulls the oscillator
        A(1, i + 1) = -1.0;
    }
    Eigen::VectorXd y0(n);
    for (int i = 0; i < n; ++i) y0[i] = 0.1 * (i + 1) * (i % 2 ? -1 : 1);
    OdeArrow f;
    f.f = [&](double, const double* y, double* ydot) {
        Eigen::Map<Eigen::VectorXd>(ydot, n) = A * Eigen::Map<const Eigen::VectorXd>(y, n);
    };
    f.numCoupled = nc;
    for (int b = 0; b < nb; ++b) {
        f.first.push_back(nc + 2 * b);
        f.size.push_back(2);
    }
    IntegrationSettings settings;
    settings.accuracy = 1e-8;
    std::vector<double> y(y0.data(), y0.data() + n);
    double worst = 0;
    int samples = 0;
    const IntegrationStats stats = integrateSampled(f, 0.0, y, 2.0, 50.0, {}, settings, [&](double t, const double* ys) {
        const Eigen::VectorXd exact = (A * t).exp() * y0;
        for (int i = 0; i < n; ++i) worst = std::max(worst, std::abs(ys[i] - exact[i]));
        ++samples;
    });
    EXPECT_EQ(samples, 101);
    EXPECT_LE(worst, kAbsTol);
    EXPECT_LT(stats.steps, 2000);   // implicit: far beyond the explicit limit 2 / (2 x 1000) s
    // The factorisation is P^-1 exactly and the Krylov operator the same J: at most one iteration per
    // solve (none when the residual is already small).
    EXPECT_GT(stats.newtonIterations, 0);
    EXPECT_LE(stats.krylovIterations, stats.newtonIterations);
    // The blocks must follow the coupled states and cover y.
    f.first[1] = nc + 3;
    EXPECT_THROW(integrateSampled(f, 0.0, y, 1.0, 10.0, {}, settings, [](double, const double*) {}),
                 std::invalid_argument);
}
