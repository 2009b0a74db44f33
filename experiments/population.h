// Populations of virtual subjects: a YAML file gives the distributions around a base model
// (strength, tendon and fascicle lengths, fibre composition, effort, transducer noise); drawSubject
// makes person `index` of a seeded population, reproducibly from (seed, index) alone.
//
// Strength is drawn in two levels, as people differ: ln(mass scale of muscle m) = a + b_m with a
// person's level a ~ N(ln mean_scale, subject_sd^2) shared by every muscle (a strong person is strong
// everywhere) and b_m ~ N(0, muscle_sd^2) per muscle. Specific tension (sigma, so F0 without mass) and
// size (every length: path points and wrap surfaces, segment lengths, the strap and A, B, and each
// muscle's L0 and L0T; moment arms scale with it) are person-level ln-normal scales; they come from a
// stream of their own ({seed, index, 1}), so populations without them draw exactly as before. Lengths: scale ~ N(1, sd^2) per muscle, truncated at 3 sd.
// Slow fraction: F_slow + N(0, sd^2), clipped to [0.05, 0.95]. A muscle's lengths are redrawn while its
// relaxed (Virtual Muscle) fascicle at the longest path (P_max) would pass 95 % of the model's nf limit (such a person
// could not extend the elbow within the model's validity), so length draws are slightly narrower than
// stated for muscles near that limit. Effort: voluntary activation and co-contraction uniform in
// their ranges; trial CV as given. Every draw comes from one PortableRandom seeded with {seed, index}
// (the same draws with every standard library), in a fixed order, so subject k does not depend on how
// many subjects are drawn or in what order.
#pragma once

#include "model/model_file.h"

#include <string>
#include <vector>

namespace armsim {

/// A closed interval a uniform draw comes from.
struct UniformRange {
    double min = 0;  ///< lower end
    double max = 0;  ///< upper end (>= min)
};

/// Distributions of a population (units as stated; all sd relative unless noted).
struct Population {
    std::string name;                   ///< for reports
    std::string file;                   ///< where it came from ("" when built in code)
    ArmSetup base;                      ///< the model every subject is drawn around
    double strengthMeanScale = 1.0;     ///< median person-level mass scale: ln(mass scale) has mean ln of it [1]
    double strengthSubjectSd = 0.15;    ///< sd of the person-level ln(mass scale) [1]
    double strengthMuscleSd = 0.10;     ///< sd of the per-muscle ln(mass scale) around it [1]
    double tendonLengthSd = 0.05;       ///< relative sd of each muscle's L0T [1]
    double fascicleLengthSd = 0.05;     ///< relative sd of each muscle's L0 [1]
    double slowFractionMeanShift = 0.0; ///< added to every muscle's F_slow before its draw [1]
    double slowFractionSd = 0.08;       ///< absolute sd of each muscle's F_slow [1]
    double specificTensionMeanScale = 1.0;  ///< median person-level scale of every muscle's sigma [1]
    double specificTensionSd = 0.0;     ///< sd of the person-level ln(sigma scale) (F0 without mass) [1]
    double geometryMeanScale = 1.0;     ///< median person-level scale of every length (paths, segments, L0, L0T) [1]
    double geometryScaleSd = 0.0;       ///< sd of the person-level ln(length scale), truncated at 3 sd [1]
    UniformRange voluntaryActivation{0.85, 1.0};  ///< U of the agonists at a maximal effort [1]
    UniformRange coContraction{0.0, 0.15};        ///< U of the antagonists during an effort [1]
    double trialCv = 0.05;              ///< trial-to-trial CV of the effort [1]
    double transducerNoise = 0.02;      ///< relative sd of each measured torque [1]
    /// FieldError naming the field ("strength.subject_sd", ...) for a value out of range.
    void validate() const;
};

/// Reads a population file (strict: unknown keys are errors; every error names file, line, key,
/// value and the expected range). `model:` is a model name or file (loadModel); `muscle_model:` (as in
/// a model file: a name or {model: NAME, COEFFICIENT: VALUE}) gives every muscle of the base that
/// muscle model, so a population of the same people (the same draws of mass, lengths, composition)
/// can have Hill-type muscles, a truth structurally unlike the identifiers' Virtual Muscle.
Population loadPopulation(const std::string& path);
/// assets/subjects/default_population.yaml.
Population loadDefaultPopulation();

/// One drawn person: the model with the person's muscles and effort, and the draws (the truth).
struct VirtualSubject {
    int index = 0;                        ///< subject number in the population
    unsigned seed = 0;                    ///< population seed
    ArmSetup setup;                       ///< muscles and effort of this person
    double transducerNoise = 0;           ///< relative sd of each measured torque [1]
    double strengthLevel = 0;             ///< the person-level ln(mass scale) a [1]
    std::vector<double> massScale;        ///< per muscle: mass / base mass [1]
    std::vector<double> tendonLengthScale;    ///< per muscle: L0T / base L0T [1]
    std::vector<double> fascicleLengthScale;  ///< per muscle: L0 / base L0 [1] (the geometry scale apart)
    double specificTensionScale = 1;      ///< the person's sigma / base sigma [1]
    double geometryScale = 1;             ///< the person's lengths / base lengths (moment arms scale with it) [1]
};

/// Scales every length of a model by g: segment lengths, the strap and the thesis's A and B, path points,
/// wrap-surface centres and radii, and each muscle's L0, L0T and P_max (so moment arms scale by g and
/// fibre operating ranges stay as they were). Masses are not changed.
void scaleGeometry(ArmSetup& setup, double g);

/// Person `index` (>= 0) of the population with this seed.
VirtualSubject drawSubject(const Population& population, unsigned seed, int index);

}  // namespace armsim
