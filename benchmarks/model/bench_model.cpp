// Speed of arm trials. Targets (issue 3): one 3 s isometric MVC trial under 20 ms; the five thesis
// angles under 100 ms on one thread and faster on two. Issue 10: a 3 s MVC of the seven-muscle elbow
// at one angle <= 40 ms; path lengths and moment arms of all its muscles at one pose <= 20 us.
#include "model/geometry.h"
#include "model/muscle_arm.h"
#include "model/mvc_curve.h"
#include "model/osim_forward.h"
#include "model/osim_trial.h"
#include "model/trial.h"

#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <unistd.h>

using namespace armsim;

namespace {

ArmSetup loadShippedModel(const char* name) {
    setenv("ARMSIM_ASSETS", ARMSIM_ASSET_DIR, 0);
    return loadModel(name);
}

const ArmSetup& subject() {
    static const ArmSetup s = loadShippedModel("thesis");
    return s;
}

const ArmSetup& elbow() {
    static const ArmSetup s = loadShippedModel("elbow");
    return s;
}

// One isometric trial per iteration; arg = sample rate.
void measureIsometricTrial(benchmark::State& state, const ArmSetup& setup, IsometricTrialSettings s) {
    s.sampleRate = double(state.range(0));
    IntegrationStats stats;
    for (auto _ : state) stats = runIsometricTrial(setup, s).summary.stats;
    state.counters["steps"] = stats.steps;
    state.counters["rhs"] = stats.realizations;  // right-hand sides, finite-difference Jacobians included
    state.counters["partial"] = stats.partialEvaluations;  // of those, one muscle (a Jacobian column)
    state.counters["jac"] = stats.jacobians;                 // Newton matrices from analytic Jacobians
}

void BM_IsometricMvcTrial(benchmark::State& state) {
    measureIsometricTrial(state, subject(), {});  // 0.5 s rest + 3 s hold at 90 deg
}
BENCHMARK(BM_IsometricMvcTrial)->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);

void BM_FiveAnglesMvc(benchmark::State& state) {
    std::vector<IsometricTrialSettings> settings;
    for (double deg : kThesisMvcAnglesDeg) {
        IsometricTrialSettings s;
        s.elbowAngle = degToRad(deg);
        settings.push_back(s);
    }
    for (auto _ : state) benchmark::DoNotOptimize(runIsometricTrials(subject(), settings, int(state.range(0))));
}
BENCHMARK(BM_FiveAnglesMvc)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FreeMovement2s(benchmark::State& state) {
    FreeMovementSettings s;
    for (auto _ : state) benchmark::DoNotOptimize(runFreeMovement(subject(), s));
}
BENCHMARK(BM_FreeMovement2s)->Unit(benchmark::kMillisecond);

// Issue 30: the seven-muscle elbow's 2 s free movement (from 150 deg, activation 0.5 from 0.2 s, into
// the flexion stop); arg 0 = FreeMovementSolver::MuscleBlocks, 1 = the whole System (SimbodySystem).
void BM_ElbowFreeMovement2s(benchmark::State& state) {
    FreeMovementSettings s;
    s.solver = state.range(0) == 0 ? FreeMovementSolver::MuscleBlocks : FreeMovementSolver::SimbodySystem;
    IntegrationStats st;
    for (auto _ : state) benchmark::DoNotOptimize(runFreeMovement(elbow(), s, &st));
    state.counters["steps"] = st.steps;
    state.counters["rhs"] = st.realizations;
    state.counters["one_muscle"] = st.partialEvaluations;
}
BENCHMARK(BM_ElbowFreeMovement2s)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Issue 10: 0.5 s rest + 3 s hold at 90 deg flexion, agonists 0.95, antagonists 0.10; arg = sample rate.
void BM_ElbowMvcTrial(benchmark::State& state) {
    IsometricTrialSettings s;
    s.activation = elbow().effort.voluntaryActivation;
    s.antagonistActivation = elbow().effort.coContraction;
    measureIsometricTrial(state, elbow(), s);
}
BENCHMARK(BM_ElbowMvcTrial)->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);

// Issue 28: the same trial on the twin (ten muscles, the forearm rotation locked at neutral).
void BM_TwinMvcTrial(benchmark::State& state) {
    static const ArmSetup twin = loadShippedModel("twin");
    IsometricTrialSettings s;
    s.activation = twin.effort.voluntaryActivation;
    s.antagonistActivation = twin.effort.coContraction;
    measureIsometricTrial(state, twin, s);
}
BENCHMARK(BM_TwinMvcTrial)->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);

// Issue 30: a 3 s MVC at 1000 Hz with Newton's matrices from the muscles' analytic Jacobians (arg 1,
// the default) or CPODES' difference quotients (arg 0): the thesis arm, the elbow, the twin.
void BM_MvcJacobian(benchmark::State& state, const char* model) {
    static const ArmSetup thesis = loadShippedModel("thesis"), elbowModel = loadShippedModel("elbow"),
                          twin = loadShippedModel("twin");
    const ArmSetup& setup = std::string(model) == "thesis" ? thesis : std::string(model) == "elbow" ? elbowModel : twin;
    IsometricTrialSettings s;
    if (setup.getNumMuscles() > 1) {
        s.activation = setup.effort.voluntaryActivation;
        s.antagonistActivation = setup.effort.coContraction;
    }
    s.analyticJacobian = state.range(1) != 0;
    measureIsometricTrial(state, setup, s);
}
BENCHMARK_CAPTURE(BM_MvcJacobian, thesis, "thesis")->Args({1000, 0})->Args({1000, 1})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MvcJacobian, elbow, "elbow")->Args({1000, 0})->Args({1000, 1})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MvcJacobian, twin, "twin")->Args({1000, 0})->Args({1000, 1})->Unit(benchmark::kMillisecond);

// Issue 29: the same trial on the twin with Hill-type muscles (2 states per muscle against Virtual
// Muscle's 14-20).
void BM_HillTwinMvcTrial(benchmark::State& state, const char* model) {
    const ArmSetup twin = [&] {
        ArmSetup s = loadShippedModel("twin");
        setMuscleModel(s, model);
        return s;
    }();
    IsometricTrialSettings s;
    s.activation = twin.effort.voluntaryActivation;
    s.antagonistActivation = twin.effort.coContraction;
    measureIsometricTrial(state, twin, s);
}
BENCHMARK_CAPTURE(BM_HillTwinMvcTrial, thelen2003, "thelen2003")->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_HillTwinMvcTrial, degroote2016, "degroote2016")->Arg(1000)->Arg(100)->Unit(benchmark::kMillisecond);

// The thesis arm with N copies of its straight biceps (m1 .. mN).
ArmSetup copiesOfTheThesisBiceps(int n) {
    ArmSetup setup = subject();
    const MuscleSpec one = setup.muscles[0];
    setup.muscles.clear();
    for (int i = 0; i < n; ++i) {
        setup.muscles.push_back(one);
        setup.muscles.back().params.name = "m" + std::to_string(i + 1);
    }
    return setup;
}

// Issue 30: the locked MVC (0.5 s rest + 3 s hold, 1000 Hz) of N copies of the thesis's straight biceps;
// arg 0 = N, arg 1 = 1 for the banded Newton solve (the default), 0 for the dense one, arg 2 = sample
// rate [Hz] (at 1000 Hz the table of every muscle's states dominates from 64 muscles on; 100 Hz shows
// the integration). Goals: time(64) / time(8) <= 10; 256 muscles <= 1 s.
void BM_LockedMvcNMuscles(benchmark::State& state) {
    const ArmSetup setup = copiesOfTheThesisBiceps(int(state.range(0)));
    IsometricTrialSettings s;
    s.bandedNewton = state.range(1) != 0;
    s.sampleRate = double(state.range(2));
    IntegrationStats stats;
    for (auto _ : state) stats = runIsometricTrial(setup, s).summary.stats;
    state.counters["steps"] = stats.steps;
    state.counters["rhs"] = stats.realizations;
}
BENCHMARK(BM_LockedMvcNMuscles)
    ->ArgsProduct({{1, 8, 16, 32, 64, 128, 256}, {1}, {1000, 100}})
    ->ArgsProduct({{1, 8, 16, 32}, {0}, {1000}})
    ->Unit(benchmark::kMillisecond);

// Issue 30: a 1 s free movement (from 150 deg, activation 0.5 from 0.2 s, 100 Hz) of N copies of the
// thesis's straight biceps; arg 0 = N, arg 1 = 0 for FreeMovementSolver::MuscleBlocks, 1 for the whole
// System. The arm reaches the flexion stop sooner with more muscles: compare time per step.
void BM_FreeMovementNMuscles(benchmark::State& state) {
    const ArmSetup setup = copiesOfTheThesisBiceps(int(state.range(0)));
    FreeMovementSettings s;
    s.duration = 1.0;
    s.sampleRate = 100;
    s.solver = state.range(1) == 0 ? FreeMovementSolver::MuscleBlocks : FreeMovementSolver::SimbodySystem;
    IntegrationStats stats;
    for (auto _ : state) benchmark::DoNotOptimize(runFreeMovement(setup, s, &stats));
    state.counters["steps"] = stats.steps;
    state.counters["rhs"] = stats.realizations;
    state.counters["one_muscle"] = stats.partialEvaluations;
}
BENCHMARK(BM_FreeMovementNMuscles)
    ->ArgsProduct({{1, 2, 4, 8, 16, 32, 64}, {0}})
    ->ArgsProduct({{1, 2, 4, 8, 16}, {1}})
    ->Unit(benchmark::kMillisecond);

// Issue 14's floor: one right-hand side of the locked elbow is every muscle's state derivative at its
// fixed path (90 deg flexion; agonists 0.95, antagonists 0.10); arg 0 = thesis arm, 1 = elbow.
void BM_LockedArmDerivative(benchmark::State& state) {
    const ArmSetup& setup = state.range(0) ? elbow() : subject();
    const MvcGeometry g = calcMvcGeometry(setup, {90});
    std::vector<VirtualMuscle> muscles;
    std::vector<std::vector<double>> y, ydot;
    std::vector<double> U;
    for (int i = 0; i < setup.getNumMuscles(); ++i) {
        muscles.emplace_back(setup.calcMuscleParameters(i));
        U.push_back(setup.muscles[i].group == MuscleGroup::Flexor ? 0.95 : 0.10);
        y.push_back(muscles.back().calcSteadyState(g.pathLength[0][i], U.back()).states);
        ydot.emplace_back(y.back().size());
    }
    for (auto _ : state)
        for (std::size_t i = 0; i < muscles.size(); ++i) {
            muscles[i].calcStateDerivative(g.pathLength[0][i], U[i], y[i].data(), ydot[i].data());
            benchmark::DoNotOptimize(ydot[i].data());
        }
}
BENCHMARK(BM_LockedArmDerivative)->Arg(0)->Arg(1);

// Issue 10: path length and virtual-work moment arm of all seven muscles at one pose (the pose changes
// every iteration so nothing is cached).
void BM_ElbowPathsAndMomentArms(benchmark::State& state) {
    ArmGeometry g(elbow());
    double q = 0.5, sum = 0;
    for (auto _ : state) {
        q = q < 2.5 ? q + 0.01 : 0.5;
        g.setElbowAngle(q + 0.7);
        for (int i = 0; i < g.getNumMuscles(); ++i) sum += g.calcPathLength(i) + g.calcMomentArm(i);
    }
    benchmark::DoNotOptimize(sum);
}
BENCHMARK(BM_ElbowPathsAndMomentArms)->Unit(benchmark::kMicrosecond);

// The steady MVC curve of `armsim model show` (both efforts, 29 angles).
void BM_ElbowSteadyMvcCurve(benchmark::State& state) {
    std::vector<double> q;
    for (double a = 0; a <= 140; a += 5) q.push_back(a);
    for (auto _ : state)
        for (MuscleGroup g : {MuscleGroup::Flexor, MuscleGroup::Extensor})
            benchmark::DoNotOptimize(calcSteadyMvcCurve(elbow(), g, elbow().effort, q));
}
BENCHMARK(BM_ElbowSteadyMvcCurve)->Unit(benchmark::kMillisecond);

// loadModel("elbow") as a command's second load (the model reused: its files re-read and compared)
// and as a first load (a copy of the file with a comment that changes every iteration).
void BM_LoadElbowModel(benchmark::State& state) {
    const bool reused = state.range(0) == 1;
    std::ifstream in(std::string(ARMSIM_ASSET_DIR) + "/models/elbow.yaml");
    std::stringstream text;
    text << in.rdbuf();
    const std::string body = std::regex_replace(text.str(), std::regex("\\.\\./muscles/"),
                                                std::string(ARMSIM_ASSET_DIR) + "/muscles/");
    const std::string file = (std::filesystem::temp_directory_path() /
                              ("armsim_bench_elbow_" + std::to_string(::getpid()) + ".yaml")).string();
    std::ofstream(file) << body;
    loadShippedModel(file.c_str());
    long n = 0;
    for (auto _ : state) {
        if (!reused) {
            state.PauseTiming();
            std::ofstream(file) << body << "# " << ++n << "\n";
            state.ResumeTiming();
        }
        benchmark::DoNotOptimize(loadModel(file));
    }
    std::filesystem::remove(file);
}
BENCHMARK(BM_LoadElbowModel)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// arm26 (.osim) forward dynamics, 1 s, driven by the OpenSim tutorial's controls, 200 Hz states, CPodes
// at OpenSim's tolerance 1e-5 (issue 29's goal: <= 50 ms): under OpenSim 2.x's Thelen from the
// reference's first row (the comparison the tests make), and under the file's own OpenSim 4 Thelen from
// equilibrium. The model is read once; each iteration builds the System and integrates.
void BM_Arm26Forward(benchmark::State& state, const char* muscleModel) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    const std::string dir = std::string(ARMSIM_ASSET_DIR) + "/../tests/data/opensim/arm26_forward/";
    const OsimStorage controls = readOsimStorage(dir + "arm26_controls.sto");
    const OsimStorage initial = readOsimStorage(dir + "arm26_states.sto");
    OsimForwardSettings s;
    s.finalTime = 1.0;
    s.muscleModel = muscleModel;
    int steps = 0, realizations = 0;
    for (auto _ : state) {
        const OsimForwardResult r = runOsimForward(model, controls, *muscleModel ? &initial : nullptr, s);
        steps = r.stats.steps;
        realizations = r.stats.realizations;
        benchmark::DoNotOptimize(r.states.getNumRows());
    }
    state.counters["steps"] = steps;
    state.counters["realizations"] = realizations;
}
BENCHMARK_CAPTURE(BM_Arm26Forward, thelen2003_opensim2, "thelen2003_opensim2")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Arm26Forward, thelen2003, "")->Unit(benchmark::kMillisecond);

// arm26's isometric trial (model/osim_trial.h): the elbow locked at 80 deg, 0.5 s rest and a 3 s flexion
// effort sampled at 1000 Hz, as the armsim models' MVC benchmarks; the model read once, each iteration
// builds the System for the geometry and integrates the six muscles at their fixed paths.
void BM_Arm26IsometricTrial(benchmark::State& state) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    OsimIsometricTrialSettings s;
    s.coordinate = "r_elbow_flex";
    s.angleDeg = 80;
    int steps = 0;
    for (auto _ : state) {
        const OsimIsometricTrialResult r = runOsimIsometricTrial(model, s);
        steps = r.summary.stats.steps;
        benchmark::DoNotOptimize(r.summary.meanTaredTorque);
    }
    state.counters["steps"] = steps;
}
BENCHMARK(BM_Arm26IsometricTrial)->Unit(benchmark::kMillisecond);

// arm26's free trial: the elbow from 20 deg, the flexors at 0.2 from 0.2 s, 1 s at 200 Hz (CPodes 1e-5).
void BM_Arm26FreeTrial(benchmark::State& state) {
    const OsimModel model = readOsimFile(std::string(ARMSIM_ASSET_DIR) + "/models/arm26.osim");
    OsimFreeMovementSettings s;
    s.coordinate = "r_elbow_flex";
    s.initialAngleDeg = 20;
    s.activation = 0.2;
    s.duration = 1;
    IntegrationStats stats;
    for (auto _ : state) {
        const Table t = runOsimFreeMovement(model, s, &stats);
        benchmark::DoNotOptimize(t.getNumRows());
    }
    state.counters["steps"] = stats.steps;
}
BENCHMARK(BM_Arm26FreeTrial)->Unit(benchmark::kMillisecond);

}  // namespace
