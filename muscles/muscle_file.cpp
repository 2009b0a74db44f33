#include "muscles/muscle_file.h"

#include "basics/bound.h"
#include "basics/files.h"
#include "basics/param_node.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>

#ifndef ARMSIM_ASSET_DIR
#define ARMSIM_ASSET_DIR "assets"
#endif

namespace armsim {

std::string getAssetDirectory() {
    std::error_code ec;
    const char* env = std::getenv("ARMSIM_ASSETS");
    if (env && *env) {
        // A folder without models/ is not an assets folder: say so once, by the variable's name, instead
        // of a missing-file error about whichever asset is read first.
        if (!std::filesystem::is_directory(std::filesystem::path(env) / "models", ec))
            throw InputError(std::string("ARMSIM_ASSETS = '") + env +
                             "': not an armsim assets folder (expected its models/, muscles/, subjects/ ...); "
                             "unset it to use the assets armsim was built or installed with");
        return env;
    }
    // An installed command (cmake --install): <prefix>/bin/armsim reads <prefix>/share/armsim/assets,
    // even while the source tree it was built from exists. (The installed Python package sets
    // ARMSIM_ASSETS itself: python/armsim/__init__.py.)
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec && exe.filename() == "armsim") {
        const std::filesystem::path installed = exe.parent_path().parent_path() / "share" / "armsim" / "assets";
        if (std::filesystem::is_directory(installed, ec)) return installed.string();
    }
    return ARMSIM_ASSET_DIR;   // the source tree
}

std::string findAsset(const std::string& name) {
    if (doesPathExist(name)) return name;
    const std::string inAssets = getAssetDirectory() + "/" + name;
    if (doesPathExist(inAssets)) return inAssets;
    throw InputError(name + ": no such file (looked here and in " + getAssetDirectory() +
                     "; the environment variable ARMSIM_ASSETS names another assets folder)");
}

namespace {

FibreType readFibreType(const ParamNode& n, const std::string& name) {
    FibreType t;
    t.name = name;
    const Bound any = Bound::any();
    t.beta = n.getNumber("beta", any);
    t.omega = n.getNumber("omega", any);
    t.rho = n.getNumber("rho", any);
    t.Vmax = n.getNumber("Vmax", any);
    t.cV0 = n.getNumber("cV0", any);
    t.cV1 = n.getNumber("cV1", any);
    t.bV = n.getNumber("bV", any);
    t.aV0 = n.getNumber("aV0", any);
    t.aV1 = n.getNumber("aV1", any);
    t.aV2 = n.getNumber("aV2", any);
    t.af = n.getNumber("af", any);
    t.nf0 = n.getNumber("nf0", any);
    t.nf1 = n.getNumber("nf1", any);
    t.Tf1 = n.getNumber("Tf1", any);
    t.Tf2 = n.getNumber("Tf2", any);
    t.Tf3 = n.getNumber("Tf3", any);
    t.Tf4 = n.getNumber("Tf4", any);
    t.aS1 = n.getNumber("aS1", any, 1.0);
    t.aS2 = n.getNumber("aS2", any, 1.0);
    t.TS = n.getNumber("TS", any, 1.0);
    t.cY = n.getNumber("cY", any, 0.0);
    t.VY = n.getNumber("VY", any, 1.0);
    t.TY = n.getNumber("TY", any, 1.0);
    t.f05 = n.getNumber("f05", Bound::positive("pps"), 0.0);  // optional: only the synthetic EMG needs it
    n.finish();
    n.rethrowWithLocation([&] { t.validate(n.path("")); });
    return t;
}

}  // namespace

void loadFibreTypes(const std::string& path, FibreType& slow, FibreType& fast, MuscleCoefficients& c) {
    const ParamNode root = ParamNode::loadFile(path);
    root.getString("source", "");
    slow = readFibreType(root.child("slow"), "slow");
    fast = readFibreType(root.child("fast"), "fast");
    const ParamNode w = root.child("whole_muscle");
    const Bound any = Bound::any();
    c.c1 = w.getNumber("c1", any);
    c.k1 = w.getNumber("k1", any);
    c.Lr1 = w.getNumber("Lr1", any);
    c.eta = w.getNumber("eta", any);
    c.c2 = w.getNumber("c2", any);
    c.k2 = w.getNumber("k2", any);
    c.Lr2 = w.getNumber("Lr2", any);
    c.cT = w.getNumber("cT", any);
    c.kT = w.getNumber("kT", any);
    c.LrT = w.getNumber("LrT", any);
    c.Ur = w.getNumber("Ur", any);
    c.fmin = w.getNumber("fmin", any);
    c.fmax = w.getNumber("fmax", any);
    c.sigma = w.getNumber("sigma", any);
    c.density = w.getNumber("density", any);
    w.finish();
    w.rethrowWithLocation([&] { c.validate("whole_muscle"); });
    root.finish();
}

Bound getSpecificTensionBound() { return Bound::closed(1e4, 2e6, "N/m^2, 1-200 N/cm^2"); }

Bound getMaxFiringRateBound() { return Bound{0.5, 8, true, false, "f0.5, above fmin 0.5"}; }

void readMuscleFields(const ParamNode& root, MuscleParameters& p, bool required, const MuscleDefaults& defaults) {
    const Bound any = Bound::any();
    // Each quantity in its own bound where it is typed (the derived mass and L0T are checked again).
    auto number = [&](const std::string& key, double& field) {
        const Bound bound = key == "mass"                      ? bounds::kMuscleMass
                            : key == "optimal_fascicle_length" ? getOptimalFascicleLengthBound()
                            : key == "optimal_tendon_length"   ? bounds::kTendonLength
                            : key == "max_path_length"         ? bounds::kPathLength
                                                               : any;
        if (required || root.has(key)) field = root.getNumber(key, bound);
    };
    // A field or the OpenSim quantity it is converted from (below), not both.
    auto numberOrConverted = [&](const std::string& key, const std::string& converted, double& field) {
        if (!root.has(converted)) return number(key, field);
        if (root.has(key))
            throw InputError(root.where(converted) + ": give either '" + key + "' or '" + converted + "', not both");
    };
    const int sizeKeys = int(root.has("mass")) + int(root.has("max_isometric_force")) + int(root.has("volume"));
    if (sizeKeys > 1)
        throw InputError(root.where() + ": give one of 'mass', 'max_isometric_force' and 'volume', not " +
                         std::to_string(sizeKeys));
    if (required && !root.has("max_isometric_force") && !root.has("volume")) number("mass", p.mass);
    if (!required && root.has("mass")) number("mass", p.mass);
    number("optimal_fascicle_length", p.optimalFascicleLength);
    numberOrConverted("optimal_tendon_length", "tendon_slack_length", p.optimalTendonLength);
    if (root.has("max_path_length") || required) number("max_path_length", p.maxPathLength);
    if (root.has("pennation_angle"))
        p.pennationAngle = root.getNumber("pennation_angle", Bound{0, 1.5707963267948966, false, true, "rad"});

    if (required || root.has("fibre_fractions")) {
        const ParamNode fr = root.child("fibre_fractions");
        p.slowFraction = fr.getNumber("slow", Bound::closed(0, 1));
        const double fastFraction = fr.getNumber("fast", Bound::closed(0, 1));
        constexpr double kFractionSumTol = 1e-9;
        if (std::abs(p.slowFraction + fastFraction - 1.0) > kFractionSumTol)
            throw InputError(fr.where("fast") + ": fibre_fractions slow + fast = " +
                             std::to_string(p.slowFraction + fastFraction) + ": expected 1 (they share the PCSA)");
        fr.finish();
    }
    if (required || root.has("motor_units")) {
        const ParamNode mu = root.child("motor_units");
        p.numSlowUnits = mu.getInt("slow", 0, int(bounds::kMotorUnits.hi));
        p.numFastUnits = mu.getInt("fast", 0, int(bounds::kMotorUnits.hi));
        if (p.numSlowUnits + p.numFastUnits == 0)  // (a composition grid's 0 + 0 cell is made in code, not read)
            throw InputError(mu.where("fast") + ": motor_units slow + fast = 0: expected at least one motor unit "
                                                "(without units a muscle makes no active force)");
        p.apportioning = mu.getChoice("apportioning", {"thesis", "equal"}, "thesis") == "equal"
                             ? Apportioning::Equal : Apportioning::Thesis;
        mu.finish();
    }
    const bool readsTypes = required || root.has("fibre_types");
    if (readsTypes) {
        const std::string typesFile = root.findFile("fibre_types", "fibre-type file");
        loadFibreTypes(typesFile, p.slow, p.fast, p.coefficients);
    }
    // The model's defaults replace the fibre-type file's values just read (not values read earlier,
    // e.g. from a `parameters:` file), then the muscle's own keys replace both.
    if (readsTypes && defaults.specificTension > 0) p.coefficients.sigma = defaults.specificTension;
    if (root.has("specific_tension"))
        p.coefficients.sigma = root.getNumber("specific_tension", getSpecificTensionBound());
    if (readsTypes && defaults.maxFiringRate > 0) p.coefficients.fmax = defaults.maxFiringRate;
    if (root.has("max_firing_rate")) p.coefficients.fmax = root.getNumber("max_firing_rate", getMaxFiringRateBound());
    // Conversions need the coefficients (sigma, rho, LrT), so they come last.
    if (root.has("volume"))
        p.mass = root.getNumber("volume", Bound{0, 0.01, true, false, "m^3"}) * p.coefficients.density;
    if (root.has("max_isometric_force")) {
        // A human muscle's F0 is a few kN at most (quadriceps heads in OpenSim models: under 5 kN).
        const double F0 = root.getNumber("max_isometric_force", bounds::kMaxIsometricForce);
        p.mass = F0 * p.optimalFascicleLength * p.coefficients.density / p.coefficients.sigma;
    }
    if (root.has("tendon_slack_length")) {
        const double slack = root.getNumber("tendon_slack_length", bounds::kTendonLength);
        p.optimalTendonLength = slack / p.coefficients.LrT;
    }
}

MuscleParameters loadMuscleParameters(const std::string& path, const MuscleDefaults& defaults) {
    const ParamNode root = ParamNode::loadFile(path);
    MuscleParameters p;
    p.name = root.getString("name");
    root.getString("source", "");
    readMuscleFields(root, p, true, defaults);
    root.finish();
    root.rethrowWithLocation([&] { p.validate(); });
    return p;
}

}  // namespace armsim
