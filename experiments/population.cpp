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

void Population::validate() const {
    checkField("strength.subject_sd", strengthSubjectSd, Bound::closed(0, 1));
    checkField("strength.muscle_sd", strengthMuscleSd, Bound::closed(0, 1));
    checkField("tendon_length.sd", tendonLengthSd, Bound{0, 1.0 / 3, false, true, "relative sd, < 1/3"});
    checkField("fascicle_length.sd", fascicleLengthSd, Bound{0, 1.0 / 3, false, true, "relative sd, < 1/3"});
    checkField("slow_fraction.sd", slowFractionSd, Bound::closed(0, 0.5));
    checkRange("voluntary_activation", voluntaryActivation, Bound{0, 1, true, false, "in (0, 1]"});
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
    if (root.has("strength")) {
        const ParamNode s = root.child("strength");
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
    readSd("slow_fraction", p.slowFractionSd);
    p.voluntaryActivation = readRange(root, "voluntary_activation", p.voluntaryActivation);
    p.coContraction = readRange(root, "co_contraction", p.coContraction);
    p.trialCv = root.getNumber("trial_cv", Bound::any(), p.trialCv);
    p.transducerNoise = root.getNumber("transducer_noise", Bound::any(), p.transducerNoise);
    root.finish();
    try {
        p.validate();
    } catch (const FieldError& e) {
        const std::string key = e.getField().substr(0, e.getField().find('.'));  // the top-level key
        throw InputError((root.has(key) ? root.where(key) : path) + ": field '" + e.getField() + "' " + e.getDetail());
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
    v.strengthLevel = population.strengthSubjectSd * rng.drawNormal();
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
            m.params.slowFraction = std::clamp(base.slowFraction + slow, 0.05, 0.95);
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
