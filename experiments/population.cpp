#include "experiments/population.h"

#include "basics/param_node.h"
#include "basics/portable_random.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <cmath>

namespace armsim {

namespace {

// Largest relaxed fascicle length at the longest path, as a fraction of the nf limit: room for the
// stretch of a co-contracting antagonist.
constexpr double kMaxRelaxedStretch = 0.95;

void checkRange(const std::string& field, const UniformRange& r, const Bound& bound) {
    checkField(field + ".min", r.min, bound);
    checkField(field + ".max", r.max, Bound{r.min, bound.hi, false, bound.hiOpen, ">= min"});
}

UniformRange readRange(const ParamNode& node, const std::string& key, const UniformRange& fallback) {
    if (!node.has(key)) return fallback;
    const ParamNode r = node.child(key);
    const UniformRange out{r.getNumber("min", Bound::any()), r.getNumber("max", Bound::any())};
    r.finish();
    return out;
}

// N(0, 1) truncated at +/- 3 (a length scale of 1 +/- 3 sd stays positive for sd < 1/3).
double drawTruncatedNormal(PortableRandom& rng) {
    for (;;) {
        const double z = rng.drawNormal();
        if (std::abs(z) <= 3) return z;
    }
}

}  // namespace

void scaleGeometry(ArmSetup& setup, double g) {
    checkField("geometry scale", g, Bound::closed(0.25, 4));
    ArmParameters& a = setup.arm;
    for (double* x : {&a.upperArmLength, &a.forearmLength, &a.handLength, &a.originDistance, &a.insertionDistance,
                      &a.strapDistance})
        *x *= g;
    for (double& c : a.forearmRotation.axisPoint) c *= g;
    for (MuscleSpec& m : setup.muscles) {
        for (PathElementSpec& e : m.path) {
            for (double& c : e.location) c *= g;
            e.radius *= g;
        }
        for (MuscleParameters* p : {&m.params, &m.sourceParams}) {
            p->optimalFascicleLength *= g;
            p->optimalTendonLength *= g;
            p->maxPathLength *= g;
        }
    }
}

void Population::validate() const {
    checkField("strength.mean_scale", strengthMeanScale, Bound::closed(0.25, 4));
    checkField("strength.subject_sd", strengthSubjectSd, Bound::closed(0, 1));
    checkField("strength.muscle_sd", strengthMuscleSd, Bound::closed(0, 1));
    checkField("tendon_length.sd", tendonLengthSd, Bound{0, 1.0 / 3, false, true, "relative sd, < 1/3"});
    checkField("fascicle_length.sd", fascicleLengthSd, Bound{0, 1.0 / 3, false, true, "relative sd, < 1/3"});
    checkField("slow_fraction.sd", slowFractionSd, Bound::closed(0, 0.5));
    checkField("slow_fraction.mean_shift", slowFractionMeanShift, Bound::closed(-0.5, 0.5));
    checkField("specific_tension.mean_scale", specificTensionMeanScale, Bound::closed(0.25, 4));
    checkField("specific_tension.sd", specificTensionSd, Bound::closed(0, 1));
    checkField("geometry.mean_scale", geometryMeanScale, Bound::closed(0.5, 2));
    checkField("geometry.scale_sd", geometryScaleSd, Bound::closed(0, 0.2));
    checkRange("voluntary_activation", voluntaryActivation, Bound{0, 1, true, false, "fraction of maximal drive"});
    checkRange("co_contraction", coContraction, Bound::closed(0, 1));
    checkField("trial_cv", trialCv, Bound::closed(0, 0.5));
    checkField("transducer_noise", transducerNoise, Bound::closed(0, 0.5));
}

Population loadPopulation(const std::string& path) {
    const ParamNode root = ParamNode::loadFile(path);
    Population p;
    p.file = path;
    p.name = root.getString("name");
    root.getString("description", "");
    const std::string model = root.getString("model");
    const bool isName = model.find('/') == std::string::npos && model.find(".yaml") == std::string::npos;
    try {
        p.base = loadModel(isName ? model : root.findFile("model", "model file"));
    } catch (const InputError& e) {
        throw InputError(root.where("model") + ": field 'model' = '" + model + "': " + e.what());
    }
    if (root.has("muscle_model")) readMuscleModelKey(root, p.base);
    if (root.has("strength")) {
        const ParamNode s = root.child("strength");
        p.strengthMeanScale = s.getNumber("mean_scale", Bound::any(), p.strengthMeanScale);
        p.strengthSubjectSd = s.getNumber("subject_sd", Bound::any(), p.strengthSubjectSd);
        p.strengthMuscleSd = s.getNumber("muscle_sd", Bound::any(), p.strengthMuscleSd);
        s.finish();
    }
    auto readSd = [&](const std::string& key, double& sd) {
        if (!root.has(key)) return;
        const ParamNode n = root.child(key);
        sd = n.getNumber("sd", Bound::any(), sd);
        n.finish();
    };
    readSd("tendon_length", p.tendonLengthSd);
    readSd("fascicle_length", p.fascicleLengthSd);
    if (root.has("slow_fraction")) {
        const ParamNode n = root.child("slow_fraction");
        p.slowFractionSd = n.getNumber("sd", Bound::any(), p.slowFractionSd);
        p.slowFractionMeanShift = n.getNumber("mean_shift", Bound::any(), p.slowFractionMeanShift);
        n.finish();
    }
    if (root.has("specific_tension")) {
        const ParamNode n = root.child("specific_tension");
        p.specificTensionMeanScale = n.getNumber("mean_scale", Bound::any(), p.specificTensionMeanScale);
        p.specificTensionSd = n.getNumber("sd", Bound::any(), p.specificTensionSd);
        n.finish();
    }
    if (root.has("geometry")) {
        const ParamNode n = root.child("geometry");
        p.geometryMeanScale = n.getNumber("mean_scale", Bound::any(), p.geometryMeanScale);
        p.geometryScaleSd = n.getNumber("scale_sd", Bound::any(), p.geometryScaleSd);
        n.finish();
    }
    p.voluntaryActivation = readRange(root, "voluntary_activation", p.voluntaryActivation);
    p.coContraction = readRange(root, "co_contraction", p.coContraction);
    p.trialCv = root.getNumber("trial_cv", Bound::any(), p.trialCv);
    p.transducerNoise = root.getNumber("transducer_noise", Bound::any(), p.transducerNoise);
    root.finish();
    try {
        p.validate();
    } catch (const FieldError& e) {
        const std::string key = e.getField().substr(0, e.getField().find('.'));  // the top-level key
        throw InputError((root.has(key) ? root.where(key) : path) + ": field " + describeField(e.getField()) + " " + e.getDetail());
    }
    return p;
}

Population loadDefaultPopulation() { return loadPopulation(findAsset("subjects/default_population.yaml")); }

VirtualSubject drawSubject(const Population& population, unsigned seed, int index) {
    population.validate();
    if (index < 0) throw InputError("subject index " + std::to_string(index) + ": expected >= 0");
    PortableRandom rng{seed, unsigned(index)};

    VirtualSubject v;
    v.index = index;
    v.seed = seed;
    v.setup = population.base;
    v.transducerNoise = population.transducerNoise;
    v.strengthLevel = std::log(population.strengthMeanScale) + population.strengthSubjectSd * rng.drawNormal();
    // Person-level sigma and size, from their own stream (see population.h).
    PortableRandom person{seed, unsigned(index), 1u};
    v.specificTensionScale = population.specificTensionMeanScale * std::exp(population.specificTensionSd * person.drawNormal());
    v.geometryScale = population.geometryMeanScale * std::exp(population.geometryScaleSd * drawTruncatedNormal(person));
    if (v.geometryScale != 1) scaleGeometry(v.setup, v.geometryScale);
    if (v.specificTensionScale != 1)
        for (MuscleSpec& m : v.setup.muscles) m.params.coefficients.sigma *= v.specificTensionScale;
    for (MuscleSpec& m : v.setup.muscles) {
        const MuscleParameters base = m.params;
        const double mass = std::exp(v.strengthLevel + population.strengthMuscleSd * rng.drawNormal());
        const double slow = population.slowFractionSd * rng.drawNormal();
        double tendon = 1, fascicle = 1;
        // Lengths are redrawn until the relaxed muscle stays inside the model's range at its longest
        // path (a person whose fascicle would pass the nf limit at full extension is not drawn).
        for (int attempt = 1;; ++attempt) {
            tendon = 1 + population.tendonLengthSd * drawTruncatedNormal(rng);
            fascicle = 1 + population.fascicleLengthSd * drawTruncatedNormal(rng);
            m.params = base;
            m.params.mass *= mass;
            m.params.optimalTendonLength *= tendon;
            m.params.optimalFascicleLength *= fascicle;
            m.params.slowFraction = std::clamp(base.slowFraction + population.slowFractionMeanShift + slow, 0.05, 0.95);
            const VirtualMuscle muscle(m.params);
            const SteadyState relaxed = muscle.calcSteadyState(m.params.maxPathLength, 0.0);
            if (relaxed.converged && relaxed.states[VirtualMuscle::kL] < kMaxRelaxedStretch * muscle.getNfLimit()) break;
            if (attempt == 1000)
                throw InputError(population.file + ": muscle '" + base.name + "': no draw of its lengths in 1000 keeps "
                                 "the relaxed fascicle inside the model's range at the longest path: the length "
                                 "sd are too wide for this model");
        }
        v.massScale.push_back(mass);
        v.tendonLengthScale.push_back(tendon);
        v.fascicleLengthScale.push_back(fascicle);
    }
    auto draw = [&](const UniformRange& r) { return r.min + (r.max - r.min) * rng.drawUniform(); };
    v.setup.effort.voluntaryActivation = draw(population.voluntaryActivation);
    v.setup.effort.coContraction = draw(population.coContraction);
    v.setup.effort.trialCv = population.trialCv;
    v.setup.name = population.base.name + " subject " + std::to_string(index);
    return v;
}

}  // namespace armsim
