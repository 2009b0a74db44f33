// Validation of the torque-data identifiers on virtual subjects: each subject drawn from a population,
// its data synthesized through a protocol, identified with every method, truth beside estimate.
#pragma once

#include "basics/fields.h"

#include "basics/numbers.h"

#include "identification/torque_identification.h"

#include <functional>
#include <string>
#include <vector>

namespace armsim {

/// One identification in a validation: truth, estimate, coverage.
struct ElbowValidationRow {
    int subject = 0;
    double noise = 0;                  ///< transducer noise used [1]
    std::string method;
    double trueMass = 0, trueTendonLength = 0;   ///< the subject's primary muscle [kg], [m]
    double trueMaxForce = 0;                     ///< its F0 = sigma M / (rho L0) [N]
    MuscleEstimate estimate;
    double massError = kNaN;      ///< estimate / truth - 1 [1]
    double tendonError = kNaN;    ///< estimate - truth [m]
    int massCovered = -1;              ///< 1/0: truth inside/outside the interval; -1: no interval
    int tendonCovered = -1;
    double maxForceError = kNaN;  ///< F0 estimate / truth - 1 (methods that estimate F0) [1]
    int maxForceCovered = -1;
    /// The prior's check (ChannelFit "prior"): its chi-square tail probability; NaN without one.
    double priorCheckP = kNaN;
    // Nuisance truths, for error-vs-nuisance plots.
    double voluntaryActivation = 0, coContraction = 0, strengthLevel = 0;
    double bicepsShortScale = kNaN;  ///< second biceps head's mass scale / primary's [1]
    double synergistScale = kNaN;    ///< mean mass scale of the synergists / primary's [1]
};

/// A validation row: the subject's truth beside the estimate.
ElbowValidationRow makeElbowValidationRow(const Population& population, const VirtualSubject& subject, double noise,
                                          const std::string& method, const MuscleEstimate& estimate);

/// Bias, RMSE and coverage of one method at one noise level.
struct ElbowValidationSummary {
    std::string method;
    double noise = 0;
    int subjects = 0, converged = 0;
    double massBias = 0, massRmse = 0;        ///< relative [1]; NaN when no subject has an estimate
    double tendonBias = 0, tendonRmse = 0;    ///< [m]
    double maxForceBias = kNaN, maxForceRmse = kNaN;  ///< relative [1]; NaN without F0 estimates
    double maxForceCoverage = kNaN;
    double massCoverage = kNaN, tendonCoverage = kNaN;  ///< fraction of subjects [1]
    double massIntervalWidth = kNaN;     ///< mean 95 % interval width / estimate [1]
    double tendonIntervalWidth = kNaN;   ///< mean 95 % interval width [m]
    /// Standard errors over the subjects (NaN with fewer than 2): of the bias (the mean), of the RMSE
    /// (delta method) and of the coverage (binomial); a 95 % interval is about +/- 2 of them.
    double massBiasSe = kNaN, massRmseSe = kNaN, massCoverageSe = kNaN;
    double tendonBiasSe = kNaN, tendonRmseSe = kNaN, tendonCoverageSe = kNaN;
    /// Of the estimates with a prior check: the fraction it flags (p < 0.05; about 0.05 when the person
    /// is one of the prior's population) and the mass and L0T coverage of those it passes [1].
    double priorFlagged = kNaN;
    double massCoveragePassed = kNaN, tendonCoveragePassed = kNaN;
};

/// Settings of runElbowValidation.
struct ElbowValidationSettings {
    int subjects = 200;
    unsigned seed = 1;                        ///< population and noise seed
    std::vector<double> noiseLevels;          ///< transducer noise levels; empty: the population's
    /// > 0: also run "synergist-va", the synergist-aware identifier with voluntary activation measured
    /// by twitch interpolation to this sd [1]; 0: not.
    double activationSd = 0.02;
    TorqueProtocol protocol;
    bool freeSlowFraction = false;            ///< the synergist identifiers free the slow fractions (SynergistOptions)
    int jobs = 2;                             ///< threads (over subjects)
};

/// Draws subjects 0..subjects-1 from `truth`, synthesizes each one's data once per noise level (common
/// random numbers across levels; the channels besides torque once), identifies with every method
/// (thesis, synergist, synergist-va when activationSd > 0, and channels when the protocol records
/// channels besides torque) using `prior` as the identifiers' prior
/// and model (out of family when the two differ). Throws InputError unless the two models' primary
/// muscles have the same name. progress(done, total) per subject.
std::vector<ElbowValidationRow> runElbowValidation(const Population& truth, const Population& prior,
                                                   const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress = {});
/// The most fits (rows) one runElbowValidation makes: every row is kept in memory (and copied once).
constexpr double kMaxElbowValidationFits = 4e6;
/// The fits runElbowValidation(truth, prior, settings) makes: subjects x noise levels x methods, after
/// the same checks (InputError above kMaxElbowValidationFits, naming the three numbers).
long countElbowValidationFits(const Population& truth, const Population& prior, const ElbowValidationSettings& settings);
/// One subject of such a validation: the person, its clean (noise-free) torque data and channels as
/// synthesized, and one row per noise level and method.
struct ElbowValidationSubject {
    VirtualSubject subject;
    std::vector<TorqueObservation> torque;       ///< before transducer noise (setTransducerNoise adds it)
    std::vector<ChannelObservation> channels;    ///< empty when the protocol records only torque
    std::vector<ElbowValidationRow> rows;
};
/// Subject `index` of runElbowValidation(truth, prior, settings), alone (the same rows, computed once).
ElbowValidationSubject runElbowValidationSubject(const Population& truth, const Population& prior,
                                                 const ElbowValidationSettings& settings, int index);
/// In family: the truth population is the prior.
std::vector<ElbowValidationRow> runElbowValidation(const Population& population, const ElbowValidationSettings& settings,
                                                   const std::function<void(int, int)>& progress = {});
std::vector<ElbowValidationSummary> summarizeElbowValidation(const std::vector<ElbowValidationRow>& rows);

/// summarizeElbowValidation one row at a time, in memory independent of the number of rows (studies of
/// millions of subjects): per (method, noise) in the order of first appearance, running sums for bias,
/// RMSE and coverage and Welford updates for their standard errors.
class ElbowValidationAccumulator {
public:
    void add(const ElbowValidationRow& row);
    std::vector<ElbowValidationSummary> getSummaries() const;

private:
    struct Running {  // mean and sum of squared deviations (Welford)
        long n = 0;
        double mean = 0, m2 = 0;
        void add(double x);
    };
    struct Cell {
        std::string method;
        double noise = 0;
        int subjects = 0, converged = 0;
        int n = 0, mn = 0, mc = 0, tn = 0, tc = 0, fn = 0, fcn = 0, fc = 0;
        int pn = 0, pf = 0, pmn = 0, pmc = 0, ptn = 0, ptc = 0;  // prior check: checked, flagged, passed coverage
        double mb = 0, mm = 0, tb = 0, tm = 0, mw = 0, tw = 0, fb = 0, fm = 0;
        Running massError, massSquare, tendonError, tendonSquare;
    };
    std::vector<Cell> cells_;
};
/// The fields of a validation row and of a summary (basics/fields.h): their CSV files are made from them.
const FieldTable<ElbowValidationRow>& getElbowValidationFields();
const FieldTable<ElbowValidationSummary>& getElbowValidationSummaryFields();
/// One CSV line per row: truth, estimate, 95 % interval, coverage, nuisance truths (SI units, errors in %).
std::string formatElbowValidationCsv(const std::vector<ElbowValidationRow>& rows);
/// Per method and noise level: bias, RMSE, coverage, then their standard errors (CSV).
std::string formatElbowValidationSummaryCsv(const std::vector<ElbowValidationSummary>& summaries);

}  // namespace armsim
