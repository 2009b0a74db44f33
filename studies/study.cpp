#include "studies/study.h"

#include "basics/numbers.h"

#include "basics/format.h"
#include "identification/synergist_identifier.h"
#include "basics/csv.h"
#include "basics/files.h"
#include "basics/param_node.h"
#include "basics/quick_run.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <type_traits>

namespace armsim {

namespace {

constexpr long kMaxTasks = 1000000000L;
// Changes whenever a result's meaning or format changes, so old journals are not resumed into new files.
constexpr const char* kResultsVersion = "armsim-study-results-2";

std::uint64_t hashFnv1a(const std::string& text, std::uint64_t h = 1469598103934665603ULL) {
    for (unsigned char c : text) h = (h ^ c) * 1099511628211ULL;
    return h;
}

std::string toHex(std::uint64_t v) { return fmt::format("{:016x}", v); }

// Strict UTF-8: no overlong forms, surrogates or code points past U+10FFFF.
bool isValidUtf8(const std::string& text) {
    const auto* p = reinterpret_cast<const unsigned char*>(text.data());
    const auto* end = p + text.size();
    while (p < end) {
        const unsigned char c = *p;
        int n = 0;
        unsigned long cp = 0, min = 0;
        if (c < 0x80) { ++p; continue; }
        if ((c & 0xe0) == 0xc0) n = 1, cp = c & 0x1f, min = 0x80;
        else if ((c & 0xf0) == 0xe0) n = 2, cp = c & 0x0f, min = 0x800;
        else if ((c & 0xf8) == 0xf0) n = 3, cp = c & 0x07, min = 0x10000;
        else return false;
        if (end - p <= n) return false;
        for (int k = 1; k <= n; ++k) {
            if ((p[k] & 0xc0) != 0x80) return false;
            cp = (cp << 6) | (p[k] & 0x3f);
        }
        if (cp < min || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return false;
        p += n + 1;
    }
    return true;
}

// Resolves a file named in the study: relative to the study file's folder, then as given.
std::string resolveStudyFile(const ParamNode& n, const std::string& field, const std::string& value, const char* what) {
    namespace fs = std::filesystem;
    const fs::path p(value);
    if (p.is_relative() && !n.getDirectory().empty()) {
        const fs::path beside = fs::path(n.getDirectory()) / p;
        if (isRegularFile(beside.string())) return beside.string();
    }
    if (isRegularFile(p.string())) return p.string();
    throw InputError(n.where(field) + ": field " + describeField(field) + " = '" + value + "': no such " + what +
                     " (looked beside the study file and in the working directory)");
}

}  // namespace

void Study::setPopulation(const Population& population, const std::string& reference) {
    truths = {StudyTruth{reference, population.name, population}};
    priorReference.clear();
    prior = population;
}

void Study::validate() const {
    if (truths.empty()) throw FieldError("truths", "is empty: expected at least one truth population");
    if (truths.size() > 1 && priorReference.empty())
        throw FieldError("prior", "is missing: several truths need the population the identifiers assume (`prior:`)");
    prior.validate();
    checkIdentifiablePrior(prior);
    prior.base.requireVirtualMuscles("the identifiers (prior population '" + prior.name + "')");
    const std::string& priorPrimary = prior.base.muscles.at(prior.base.primary).params.name;
    for (std::size_t i = 0; i < truths.size(); ++i) {
        const std::string field = truths.size() == 1 ? std::string("truth") : "truths[" + std::to_string(i) + "]";
        truths[i].population.validate();
        const Population& t = truths[i].population;
        const std::string& truthPrimary = t.base.muscles.at(t.base.primary).params.name;
        if (truthPrimary != priorPrimary)
            throw FieldError(field, "= '" + truths[i].reference + "': its primary muscle is '" + truthPrimary +
                                        "' but the prior identifies '" + priorPrimary + "': expected the same muscle");
        if (truths[i].label.empty()) throw FieldError(field + ".label", "is empty: expected a name");
        for (std::size_t j = 0; j < i; ++j)
            if (truths[j].label == truths[i].label)
                throw FieldError(field + ".label", "= '" + truths[i].label + "': also the label of entry " + std::to_string(j + 1) +
                                                       ": expected unique labels (set `label:`)");
    }
    checkField("subjects", subjects, Bound::closed(1, 1e7));
    if (protocols.empty()) throw FieldError("protocols", "is empty: expected at least one protocol");
    if (noiseLevels.empty()) throw FieldError("noise_levels", "is empty: expected at least one noise level");
    if (methods.empty()) throw FieldError("methods", "is empty: expected at least one identifier");
    for (std::size_t i = 0; i < noiseLevels.size(); ++i)
        checkField("noise_levels[" + std::to_string(i) + "]", noiseLevels[i], Bound{0, 0.5, false, true, "relative sd"});
    for (std::size_t i = 0; i < protocols.size(); ++i) {
        protocols[i].protocol.validate();
        for (std::size_t j = 0; j < i; ++j)
            if (protocols[j].protocol.name == protocols[i].protocol.name)
                throw FieldError("protocols[" + std::to_string(i) + "]",
                                 "= '" + protocols[i].reference + "': its name '" + protocols[i].protocol.name +
                                     "' is also that of entry " + std::to_string(j + 1) + ": expected unique protocol names");
    }
    // Names go into CSV cells, journal lines and plot legends: no control characters (they would not
    // round-trip) and UTF-8 (PLplot cannot draw other bytes). The message shows bytes as \xNN.
    auto checkName = [](const std::string& field, const std::string& name) {
        for (unsigned char c : name)
            if (c < 0x20 || c == 0x7f)
                throw FieldError(field, "= '" + name + "': expected a name without tabs, newlines or control characters");
        if (!isValidUtf8(name)) {
            std::string shown;
            for (unsigned char c : name) shown += c < 0x80 ? std::string(1, char(c)) : fmt::format("\\x{:02x}", c);
            throw FieldError(field, "= '" + shown + "': not UTF-8 text (save the file as UTF-8)");
        }
    };
    checkName("name", name);
    // The default output folder is out/study/<name>: a name with a path in it would write elsewhere.
    if (name.empty() || name == "." || name == ".." || name.find_first_of("/\\") != std::string::npos)
        throw FieldError("name", "= '" + name + "': expected a name without '/', '\\' or dots alone (the default "
                                 "output folder is out/study/<name>)");
    for (std::size_t i = 0; i < truths.size(); ++i) checkName("truths[" + std::to_string(i) + "].label", truths[i].label);
    for (std::size_t i = 0; i < protocols.size(); ++i)
        checkName("protocols[" + std::to_string(i) + "].name", protocols[i].protocol.name);
    for (std::size_t i = 0; i < methods.size(); ++i) checkName("methods[" + std::to_string(i) + "].label", methods[i].label);
    const auto& kinds = getElbowMethodKinds();
    for (std::size_t i = 0; i < methods.size(); ++i) {
        const std::string f = "methods[" + std::to_string(i) + "]";
        if (std::find(kinds.begin(), kinds.end(), methods[i].kind) == kinds.end()) {
            std::string names;
            for (const std::string& k : kinds) names += (names.empty() ? "" : ", ") + k;
            throw FieldError(f + ".method", "= '" + methods[i].kind + "': expected one of " + names);
        }
        if (methods[i].label.empty()) throw FieldError(f + ".label", "is empty: expected a name");
        for (std::size_t j = 0; j < i; ++j)
            if (methods[j].label == methods[i].label)
                throw FieldError(f + ".label", "= '" + methods[i].label + "': also the label of entry " + std::to_string(j + 1) +
                                                   ": expected unique labels");
        // channels: 0 leaves voluntary activation unmeasured; synergist-va needs a measurement.
        checkField(f + ".activation_sd", methods[i].options.activationSd,
                   Bound{0, 0.5, methods[i].kind != "channels", false});
        if (std::isfinite(methods[i].options.noiseLevel))
            checkField(f + ".noise_level", methods[i].options.noiseLevel, Bound::closed(kMinTorqueNoiseLevel, 0.5, "relative sd"));
    }
    // A study in which every identifier skips every protocol (channels on torque-only protocols) would
    // compute nothing.
    const bool anyRuns = std::any_of(methods.begin(), methods.end(), [&](const ElbowMethod& m) {
        return m.kind != "channels" || std::any_of(protocols.begin(), protocols.end(),
                                                   [](const StudyProtocol& p) { return p.protocol.hasChannels(); });
    });
    if (!anyRuns)
        throw FieldError("methods", "lists only 'channels', and no protocol records a channel besides torque: every task "
                                    "would be skipped: expected a protocol with channels or another method");
    if (getNumTasks() > kMaxTasks)
        throw FieldError("subjects", "x truths x protocols x noise levels x methods = " + std::to_string(getNumTasks()) +
                                         " tasks: expected at most " + std::to_string(kMaxTasks));
}

Study readStudy(const std::string& path) {
    const ParamNode n = ParamNode::loadFile(path);
    Study s;
    s.file = path;
    if (n.getString("kind", "") != "study")
        throw InputError(n.where("kind") + ": field 'kind' = '" + n.getString("kind", "") +
                         "': expected 'study' (a study file starts with `kind: study`)");
    s.name = n.getString("name", std::filesystem::path(path).stem().string());
    s.description = n.getString("description", "");
    const int truthKeys = int(n.has("population")) + int(n.has("truth")) + int(n.has("truths"));
    if (truthKeys > 1)
        throw InputError(n.where(n.has("truths") ? "truths" : "truth") +
                         ": give one of 'population' (in family), 'truth' or 'truths' (with 'prior'), not several");
    auto loadStudyPopulation = [](const ParamNode& node, const char* key, const std::string& reference) {
        return reference == "default" ? loadDefaultPopulation()
                                      : loadPopulation(resolveStudyFile(node, key, reference, "population file"));
    };
    if (n.has("truths")) {
        if (!n.has("prior"))
            throw InputError(n.where("truths") + ": field 'truths' needs 'prior' (the population the identifiers assume)");
        std::map<std::string, std::string> listed;   // each truth's population (its file), where it is first
        for (const ParamNode& t : n.children("truths")) {
            StudyTruth truth;
            truth.reference = t.getString("population");
            truth.population = loadStudyPopulation(t, "population", truth.reference);
            truth.label = t.getString("label", truth.population.name);
            t.finish();
            // The same people twice under two labels would run every task twice and read as two results.
            std::error_code ec;
            const std::string same = truth.population.file.empty()
                                         ? truth.reference
                                         : std::filesystem::weakly_canonical(truth.population.file, ec).string();
            if (const auto [first, fresh] = listed.emplace(same, t.where("population")); !fresh)
                throw InputError(t.where("population") + ": truth population '" + truth.reference + "' is also the truth at " +
                                 first->second + ": expected each population once (a second label runs the same people again)");
            s.truths.push_back(std::move(truth));
        }
        if (s.truths.empty()) throw InputError(n.where("truths") + ": field 'truths' is an empty list: expected at least one");
    } else {
        const char* truthKey = n.has("truth") ? "truth" : "population";
        StudyTruth truth;
        truth.reference = n.getString(truthKey, "default");
        truth.population = loadStudyPopulation(n, truthKey, truth.reference);
        truth.label = truth.population.name;
        s.truths.push_back(std::move(truth));
    }
    s.priorReference = n.getString("prior", "");
    s.prior = s.priorReference.empty() ? s.truths.front().population : loadStudyPopulation(n, "prior", s.priorReference);
    s.subjects = capForQuickRun(n.getInt("subjects", 1, 10000000), kQuickSubjects, "study subjects");
    s.seed = unsigned(n.getInt("seed", 0, 2147483647, 1));
    const std::vector<std::string> protocols = n.getStrings("protocols");
    for (std::size_t i = 0; i < protocols.size(); ++i) {
        StudyProtocol p;
        p.reference = protocols[i];
        if (p.reference != "thesis")
            p.protocol = readTorqueProtocol(
                resolveStudyFile(n, "protocols", p.reference, ("protocol file (" + describeField("protocols[" + std::to_string(i) + "]") + ")").c_str()));
        s.protocols.push_back(p);
    }
    s.noiseLevels = n.has("noise_levels") ? n.getNumbers("noise_levels", Bound{0, 0.5, false, true, "relative sd"})
                                          : std::vector<double>{s.truths.front().population.transducerNoise};
    for (std::size_t i = 0; i < s.noiseLevels.size(); ++i)   // a level twice would be computed and written twice
        for (std::size_t j = 0; j < i; ++j)
            if (s.noiseLevels[i] == s.noiseLevels[j])
                throw InputError(n.where("noise_levels") + ": field 'noise_levels' lists " +
                                 formatNumber(s.noiseLevels[i]) + " twice: expected each level once");
    for (const ParamNode& m : n.children("methods")) {
        ElbowMethod e;
        e.kind = m.getChoice("method", getElbowMethodKinds(), "");
        // What a method kind does not use would be ignored: refused at its line.
        const bool usesActivationSd = e.kind == "synergist-va" || e.kind == "channels";
        for (const char* key : {"activation_sd", "free_slow_fraction", "include_synergists", "noise_level"}) {
            const bool used = e.kind != "thesis" && (std::string(key) != "activation_sd" || usesActivationSd);
            if (m.has(key) && !used)
                throw InputError(m.where(key) + ": field '" + key + "' with method " + e.kind +
                                 ": that method does not use it, so it would be ignored" +
                                 (std::string(key) == "activation_sd" ? " (synergist-va and channels measure activation)"
                                                                      : " (the synergist-aware methods take it)"));
        }
        e.label = m.getString("label", e.kind);
        e.options.activationSd = m.getNumber("activation_sd", Bound{0, 0.5, false, false}, 0.02);
        e.options.freeSlowFraction = m.getBool("free_slow_fraction", false);
        e.options.includeSynergists = m.getBool("include_synergists", true);
        if (m.has("noise_level")) e.options.noiseLevel = m.getNumber("noise_level", Bound::closed(kMinTorqueNoiseLevel, 0.5, "relative sd"));
        m.finish();
        s.methods.push_back(e);
    }
    s.output = n.getString("output", "out/study/" + s.name);
    n.finish();
    n.rethrowWithLocation([&] { s.validate(); });
    return s;
}

std::string calcStudyFingerprint(const Study& s) {
    std::ostringstream t;
    t << kResultsVersion << "\nsubjects " << s.subjects << "\nseed " << s.seed << "\nnoise";
    for (double v : s.noiseLevels) t << ' ' << formatNumber(v);
    for (const ElbowMethod& m : s.methods)
        t << "\nmethod " << m.label << ' ' << m.kind << ' ' << formatNumber(m.options.activationSd) << ' '
          << m.options.freeSlowFraction << ' ' << m.options.includeSynergists << ' '
          << (std::isfinite(m.options.noiseLevel) ? formatNumber(m.options.noiseLevel) : "");
    for (const StudyProtocol& p : s.protocols) t << "\nprotocol\n" << formatTorqueProtocol(p.protocol);
    for (const StudyTruth& truth : s.truths) {
        const Population& pop = truth.population;
        t << "\ntruth " << truth.label << '\n';
        if (!pop.file.empty()) t << "population\n" << readFileText(pop.file);
        if (!pop.base.file.empty()) t << "\nmodel\n" << readFileText(pop.base.file);
        for (const MuscleSpec& m : pop.base.muscles) {
            const MuscleParameters& p = m.params;
            t << "\nmuscle " << p.name << ' ' << formatNumber(p.mass) << ' ' << formatNumber(p.optimalFascicleLength)
              << ' ' << formatNumber(p.optimalTendonLength) << ' ' << formatNumber(p.maxPathLength) << ' '
              << formatNumber(p.slowFraction) << ' ' << p.numSlowUnits << ' ' << p.numFastUnits;
        }
    }
    if (!s.priorReference.empty()) {  // out of family
        t << "\nprior " << s.priorReference << '\n';
        if (!s.prior.file.empty()) t << readFileText(s.prior.file);
        if (!s.prior.base.file.empty()) t << "\nprior model\n" << readFileText(s.prior.base.file);
    }
    return toHex(hashFnv1a(t.str()));
}

StudyTask getStudyTask(const Study& s, long index) {
    if (index < 0 || index >= s.getNumTasks())
        throw std::out_of_range("study task " + std::to_string(index) + " of " + std::to_string(s.getNumTasks()));
    StudyTask t;
    t.index = index;
    const long K = long(s.methods.size()), N = long(s.noiseLevels.size()), P = long(s.protocols.size());
    t.method = int(index % K);
    index /= K;
    t.noise = int(index % N);
    index /= N;
    t.protocol = int(index % P);
    index /= P;
    t.subject = int(index % long(s.subjects));
    t.truth = int(index / long(s.subjects));
    return t;
}

std::vector<StudyResult> runStudyGroup(const Study& study, long group, const std::vector<long>& tasks, int rank) {
    checkInterruption();
    using Clock = std::chrono::steady_clock;
    const long P = long(study.protocols.size());
    const int protocol = int(group % P), subject = int((group / P) % study.subjects);
    const StudyTruth& truth = study.truths.at(std::size_t(group / P / study.subjects));
    const TorqueProtocol& pr = study.protocols[protocol].protocol;
    const auto t0 = Clock::now();
    VirtualSubject v;
    std::vector<TorqueObservation> clean;
    std::vector<ChannelObservation> channels;
    std::string synthesisError;
    try {
        v = drawSubject(truth.population, study.seed, subject);
        clean = synthesizeTorqueData(v, pr, study.seed, 1);
        if (pr.hasChannels()) channels = synthesizeChannelData(v, pr, clean, study.seed);
    } catch (const InterruptedError&) {
        throw;  // not a failed task: the study stops and resumes later
    } catch (const std::exception& e) {
        synthesisError = std::string("synthesis: ") + e.what();
    }
    const double synthesisShare = std::chrono::duration<double>(Clock::now() - t0).count() / double(tasks.size());

    std::vector<StudyResult> out;
    std::map<int, std::vector<TorqueObservation>> noisy;  // by noise level
    for (long index : tasks) {
        const StudyTask t = getStudyTask(study, index);
        if (t.getGroup(study) != group) throw std::logic_error("runStudyGroup: task outside the group");
        const ElbowMethod& m = study.methods[t.method];
        const double level = study.noiseLevels[t.noise];
        const auto t1 = Clock::now();
        MuscleEstimate e;
        e.method = m.label;
        std::string error = synthesisError;
        const bool skipped = m.kind == "channels" && !pr.hasChannels();
        if (error.empty() && !skipped) {
            try {
                auto it = noisy.find(t.noise);
                if (it == noisy.end()) it = noisy.emplace(t.noise, setTransducerNoise(clean, level)).first;
                ElbowMethod method = m;  // the EMG model's crosstalk is the protocol's
                method.options.emgCrosstalk = pr.channelNoise.emgCrosstalk;
                e = identifyElbowMethod(method, study.prior, it->second, study.seed, subject, channels);
            } catch (const InterruptedError&) {
                throw;
            } catch (const std::exception& x) {
                error = x.what();
            }
        }
        StudyResult r;
        r.task = index;
        r.truth = truth.label;
        r.protocol = pr.name;
        r.rank = rank;
        r.synthesisTime = synthesisShare;
        if (!error.empty()) {
            e = MuscleEstimate();
            e.method = m.label;
            r.status = "failed";
            r.reason = error;
        } else if (skipped) {
            e.method = m.label;
            r.status = "skipped";
            r.reason = "protocol " + pr.name + " records no channel besides torque";
        } else {
            r.status = e.converged ? "ok" : std::isfinite(e.mass) ? "not-converged" : "failed";
            if (!e.converged) r.reason = e.message;
        }
        if (synthesisError.empty()) {
            try {
                r.row = makeElbowValidationRow(truth.population, v, level, m.label, e);
            } catch (const std::exception& x) {
                r.status = "failed";
                r.reason = std::string("recording: ") + x.what();
                r.row.subject = subject;
                r.row.noise = level;
                r.row.method = m.label;
                r.row.estimate = e;
            }
        } else {  // no subject: no truth
            r.row.subject = subject;
            r.row.noise = level;
            r.row.method = m.label;
            r.row.estimate = e;
            r.row.trueMass = r.row.trueTendonLength = r.row.trueMaxForce = r.row.voluntaryActivation =
                r.row.coContraction = r.row.strengthLevel = kNaN;
        }
        r.identificationTime = std::chrono::duration<double>(Clock::now() - t1).count();
        out.push_back(std::move(r));
    }
    return out;
}

// results.csv's columns: the one description of a result that results.csv's header, its rows and the
// journal's lines all follow.
#define ARMSIM_AT(member) [](auto& r) -> auto& { return r.member; }

const FieldTable<StudyResult>& getStudyResultFields() {
    using R = StudyResult;
    static const FieldTable<R> fields({
        integerField<R>("task", "", ARMSIM_AT(task)),
        textField<R>("truth", ARMSIM_AT(truth)),
        integerField<R>("subject", "", ARMSIM_AT(row.subject)),
        textField<R>("protocol", ARMSIM_AT(protocol)),
        {"method", "", [](const R& r, CsvRow& row) { row.addText(r.row.method); },
         [](const std::string& s, R& r) { return r.row.method = r.row.estimate.method = s, true; },
         [](const R& r) { return nlohmann::json(r.row.method); }, "method",
         [](const R& r) { return nlohmann::json(r.row.method); }},
        numberField<R>("noise", "1", ARMSIM_AT(row.noise)),
        textField<R>("status", ARMSIM_AT(status)),
        numberField<R>("true_mass_kg", "kg", ARMSIM_AT(row.trueMass)),
        numberField<R>("mass_kg", "kg", ARMSIM_AT(row.estimate.mass)),
        numberField<R>("mass_lower_kg", "kg", ARMSIM_AT(row.estimate.massLower)),
        numberField<R>("mass_upper_kg", "kg", ARMSIM_AT(row.estimate.massUpper)),
        numberField<R>("mass_error", "1", ARMSIM_AT(row.massError)),
        flagField<R>("mass_covered", ARMSIM_AT(row.massCovered)),
        numberField<R>("true_tendon_length_m", "m", ARMSIM_AT(row.trueTendonLength)),
        numberField<R>("tendon_length_m", "m", ARMSIM_AT(row.estimate.tendonLength)),
        numberField<R>("tendon_lower_m", "m", ARMSIM_AT(row.estimate.tendonLower)),
        numberField<R>("tendon_upper_m", "m", ARMSIM_AT(row.estimate.tendonUpper)),
        numberField<R>("tendon_error_m", "m", ARMSIM_AT(row.tendonError)),
        flagField<R>("tendon_covered", ARMSIM_AT(row.tendonCovered)),
        numberField<R>("true_max_force_N", "N", ARMSIM_AT(row.trueMaxForce)),
        numberField<R>("max_force_N", "N", ARMSIM_AT(row.estimate.maxForce)),
        numberField<R>("max_force_lower_N", "N", ARMSIM_AT(row.estimate.maxForceLower)),
        numberField<R>("max_force_upper_N", "N", ARMSIM_AT(row.estimate.maxForceUpper)),
        numberField<R>("max_force_error", "1", ARMSIM_AT(row.maxForceError)),
        flagField<R>("max_force_covered", ARMSIM_AT(row.maxForceCovered)),
        numberField<R>("noise_estimate", "1", ARMSIM_AT(row.estimate.noiseLevel)),
        numberField<R>("rms_residual_Nm", "N m", ARMSIM_AT(row.estimate.rmsResidual)),
        integerField<R>("iterations", "", ARMSIM_AT(row.estimate.iterations)),
        integerField<R>("parameters", "", ARMSIM_AT(row.estimate.numParameters)),
        numberField<R>("mass_tendon_correlation", "1", ARMSIM_AT(row.estimate.massTendonCorrelation)),
        numberField<R>("voluntary_activation", "1", ARMSIM_AT(row.voluntaryActivation)),
        numberField<R>("co_contraction", "1", ARMSIM_AT(row.coContraction)),
        numberField<R>("strength_level", "1", ARMSIM_AT(row.strengthLevel)),
        numberField<R>("biceps_short_scale", "1", ARMSIM_AT(row.bicepsShortScale)),
        numberField<R>("synergist_scale", "1", ARMSIM_AT(row.synergistScale)),
        textField<R>("reason", ARMSIM_AT(reason)),
    });
    return fields;
}

#undef ARMSIM_AT

std::string getStudyResultsHeader() { return getStudyResultFields().getHeader(); }

std::string formatStudyResult(const StudyResult& r) { return getStudyResultFields().formatRow(r).getText(); }

std::string formatStudyJournalLine(const StudyResult& r) {
    const std::string body = formatStudyResult(r) + '\t' + formatNumber(r.synthesisTime) + ',' +
                             formatNumber(r.identificationTime) + ',' + std::to_string(r.rank);
    return toHex(hashFnv1a(body)) + ' ' + body;
}

bool parseStudyJournalLine(const std::string& line, StudyResult& r) {
    if (line.size() < 18 || line[16] != ' ') return false;
    const std::string body = line.substr(17);
    if (toHex(hashFnv1a(body)) != line.substr(0, 16)) return false;
    const std::size_t tab = body.find('\t');
    if (tab == std::string::npos) return false;
    const std::vector<std::string> c = splitCsvRecord(body.substr(0, tab)),
                                   timing = splitCsvRecord(body.substr(tab + 1));
    if (timing.size() != 3) return false;
    r = StudyResult();
    if (!getStudyResultFields().parseRow(c, r)) return false;
    long rank = 0;
    if (!parseCsvNumber(timing[0], r.synthesisTime) || !parseCsvNumber(timing[1], r.identificationTime) || !parseCsvInteger(timing[2], rank))
        return false;
    r.rank = int(rank);
    r.row.estimate.converged = r.status == "ok";
    return r.status == "ok" || r.status == "not-converged" || r.status == "failed" || r.status == "skipped";
}

long peekStudyJournalTask(const std::string& line) {
    long task = -1;
    if (line.size() > 17 && line[16] == ' ') {
        const std::size_t comma = line.find(',', 17);
        if (!parseCsvInteger(line.substr(17, comma == std::string::npos ? std::string::npos : comma - 17), task)) task = -1;
    }
    return task;
}

namespace {

// Without CRLF's CR (an editor, a Windows copy), trailing blanks and a NUL-filled tail.
std::string trimJournalLine(std::string line) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t' || line.back() == '\0'))
        line.pop_back();
    return line;
}

// Calls f(raw line without '\n', whether it had one) for every line of `in`.
template <class F>
void forEachLine(std::istream& in, F f) {
    std::string raw;
    while (std::getline(in, raw)) f(raw, !in.eof());
}

}  // namespace

std::vector<StudyJournalDrop> scanStudyJournal(const std::function<std::unique_ptr<std::istream>()>& open, long numTasks,
                                               long firstLine,
                                               const std::function<void(const std::string&, StudyResult&&)>& keep) {
    std::vector<StudyJournalDrop> dropped;
    std::vector<bool> seen(std::size_t(std::max(0L, numTasks)), false);
    std::map<long, std::vector<std::size_t>> duplicates;  // task -> its entries in `dropped`
    long number = firstLine;
    std::unique_ptr<std::istream> in = open();
    forEachLine(*in, [&](const std::string& raw, bool hasEnd) {
        const std::string line = trimJournalLine(raw);
        StudyJournalDrop drop;
        drop.line = number++;
        if (line.empty()) {
            drop.kind = "blank";
            drop.detail = raw.find('\0') != std::string::npos ? "only NUL bytes (a write the file system never finished)"
                                                              : "a blank line";
            dropped.push_back(drop);
            return;
        }
        drop.task = peekStudyJournalTask(line);  // what the line says, trusted only when its checksum holds
        StudyResult r;
        if (parseStudyJournalLine(line, r)) {
            drop.task = r.task;
            if (r.task < 0 || r.task >= numTasks) {
                drop.kind = "out of range";
                drop.detail = "task " + std::to_string(r.task) + " is outside the study's 0.." + std::to_string(numTasks - 1);
            } else if (seen[std::size_t(r.task)]) {
                drop.kind = "duplicate";
                duplicates[r.task].push_back(dropped.size());
            } else {
                seen[std::size_t(r.task)] = true;
                keep(line, std::move(r));
                return;
            }
        } else if (!hasEnd) {
            drop.kind = "torn";
            drop.detail = "the last line has no line end and fails its checksum (a run stopped while writing it)";
        } else if (line.size() > 17 && line[16] == ' ' && line.find_first_not_of("0123456789abcdef") == 16) {
            drop.kind = "damaged";
            drop.detail = "its checksum does not match its text (altered or partly overwritten)";
        } else {
            drop.kind = "unreadable";
            drop.detail = "not a journal line (expected a 16-hex-digit checksum, a space and a result)";
        }
        dropped.push_back(drop);
    });
    if (duplicates.empty()) return dropped;
    // A second pass names the line each duplicate's cell was kept from (no line numbers held per task).
    std::map<long, long> keptLine;
    number = firstLine;
    in = open();
    forEachLine(*in, [&](const std::string& raw, bool) {
        const long line = number++;
        const long task = peekStudyJournalTask(raw);
        if (!duplicates.count(task) || keptLine.count(task)) return;
        StudyResult r;
        if (parseStudyJournalLine(trimJournalLine(raw), r) && r.task == task) keptLine[task] = line;
    });
    for (const auto& [task, entries] : duplicates)
        for (std::size_t e : entries)
            dropped[e].detail = "task " + std::to_string(task) + " is also line " +
                                (keptLine.count(task) ? std::to_string(keptLine[task]) : std::string("?")) + " (that one is kept)";
    return dropped;
}

StudyJournal parseStudyJournal(const std::string& text, long numTasks, long firstLine) {
    StudyJournal j;
    j.dropped = scanStudyJournal([&text] { return std::make_unique<std::istringstream>(text); }, numTasks, firstLine,
                                 [&j](const std::string& line, StudyResult&& r) {
                                     const long task = r.task;
                                     j.results.emplace(task, std::move(r));
                                     j.lines.push_back(line);
                                 });
    return j;
}

std::string summarizeStudyJournalDrops(const std::vector<StudyJournalDrop>& dropped, const StudyJournal* journal,
                                       const std::string& file) {
    return summarizeStudyJournalDrops(dropped, journal ? std::function<bool(long)>([journal](long task) {
        return journal->results.count(task) > 0;
    }) : std::function<bool(long)>(), file);
}

std::string summarizeStudyJournalDrops(const std::vector<StudyJournalDrop>& dropped,
                                       const std::function<bool(long)>& hasResult, const std::string& file) {
    if (dropped.empty()) return "";
    std::map<std::string, int> byKind;
    std::vector<long> cells;
    long unnamed = 0;
    for (const StudyJournalDrop& d : dropped) {
        ++byKind[d.kind];
        if (d.kind == "duplicate" || d.kind == "out of range" || d.kind == "blank" || d.kind == "header") continue;
        if (d.task < 0) {
            ++unnamed;
        } else if (!(hasResult && hasResult(d.task)) &&
                   std::find(cells.begin(), cells.end(), d.task) == cells.end()) {
            cells.push_back(d.task);
        }
    }
    std::string kinds;
    for (const auto& [kind, n] : byKind) kinds += (kinds.empty() ? "" : ", ") + std::to_string(n) + ' ' + kind;
    std::string text = file + ": " + std::to_string(dropped.size()) + " line" + (dropped.size() == 1 ? "" : "s") +
                       " dropped (" + kinds + ")";
    std::sort(cells.begin(), cells.end());
    if (!cells.empty()) {
        text += "; computed again: task" + std::string(cells.size() == 1 ? " " : "s ");
        for (std::size_t i = 0; i < cells.size() && i < 20; ++i) text += (i ? ", " : "") + std::to_string(cells[i]);
        if (cells.size() > 20) text += " and " + std::to_string(cells.size() - 20) + " more";
    }
    if (unnamed > 0)
        text += "; " + std::to_string(unnamed) + " line" + (unnamed == 1 ? "" : "s") +
                " named no readable task (any cell it held is computed again)";
    return text;
}

std::string formatStudyJournalDrops(const std::vector<StudyJournalDrop>& dropped) {
    std::string text;
    for (const StudyJournalDrop& d : dropped)
        text += (d.file.empty() ? "" : d.file + " ") + "line " + std::to_string(d.line) + (d.task >= 0 ? " (task " + std::to_string(d.task) + ")" : "") + ": " +
                d.kind + ": " + d.detail + '\n';
    return text;
}

std::vector<StudySummaryRow> summarizeStudy(const Study& study, const std::vector<StudyResult>& results) {
    StudySummaryAccumulator sum(study);
    for (const StudyResult& r : results) sum.add(r);
    return sum.getRows();
}

StudySummaryAccumulator::StudySummaryAccumulator(const Study& study) {
    for (const StudyTruth& t : study.truths)
        for (const StudyProtocol& p : study.protocols) {
            cells_.emplace_back();
            cells_.back().truth = t.label;
            cells_.back().protocol = p.protocol.name;
        }
}

void StudySummaryAccumulator::add(const StudyResult& r) {
    for (Cell& p : cells_) {
        if (r.protocol != p.protocol || r.truth != p.truth) continue;
        Counts& c = p.counts[{r.row.method, r.row.noise}];
        c.notConverged += r.status == "not-converged";
        c.failed += r.status == "failed";
        if (r.status == "skipped") return;
        if (r.status != "failed") return p.stats.add(r.row);
        ElbowValidationRow row = r.row;
        row.massError = row.tendonError = row.maxForceError = kNaN;
        return p.stats.add(row);
    }
}

std::vector<StudySummaryRow> StudySummaryAccumulator::getRows() const {
    std::vector<StudySummaryRow> out;
    for (const Cell& p : cells_)
        for (const ElbowValidationSummary& x : p.stats.getSummaries()) {
            StudySummaryRow row{p.truth, p.protocol, x};
            const auto it = p.counts.find({x.method, x.noise});
            if (it != p.counts.end()) row.notConverged = it->second.notConverged, row.failed = it->second.failed;
            out.push_back(row);
        }
    return out;
}

std::string formatStudySummaryCsv(const std::vector<StudySummaryRow>& rows) {
    CsvText csv({"truth", "protocol", "method", "noise", "tasks", "ok", "not_converged", "failed", "mass_bias",
                 "mass_bias_se", "mass_rmse", "mass_rmse_se", "mass_coverage", "mass_coverage_se", "mass_interval_width",
                 "tendon_bias_m", "tendon_bias_se_m", "tendon_rmse_m", "tendon_rmse_se_m", "tendon_coverage",
                 "tendon_coverage_se", "tendon_interval_width_m", "max_force_bias", "max_force_rmse",
                 "max_force_coverage"});
    for (const StudySummaryRow& r : rows) {
        const ElbowValidationSummary& x = r.stats;
        CsvRow row;
        row.addText(r.truth).addText(r.protocol).addText(x.method).addNumber(x.noise).addInteger(x.subjects);
        row.addInteger(x.converged).addInteger(r.notConverged).addInteger(r.failed);
        row.addNumber(x.massBias).addNumber(x.massBiasSe).addNumber(x.massRmse).addNumber(x.massRmseSe);
        row.addNumber(x.massCoverage).addNumber(x.massCoverageSe).addNumber(x.massIntervalWidth);
        row.addNumber(x.tendonBias).addNumber(x.tendonBiasSe).addNumber(x.tendonRmse).addNumber(x.tendonRmseSe);
        row.addNumber(x.tendonCoverage).addNumber(x.tendonCoverageSe).addNumber(x.tendonIntervalWidth);
        row.addNumber(x.maxForceBias).addNumber(x.maxForceRmse).addNumber(x.maxForceCoverage);
        csv.addRow(row);
    }
    return csv.getText();
}

}  // namespace armsim

namespace armsim {

std::string Study::describeSize() const {
    auto count = [](std::size_t n, const char* one, const char* many) {
        return std::to_string(n) + " " + (n == 1 ? one : many);
    };
    return std::to_string(getNumTasks()) + " tasks (" +
           (truths.size() > 1 ? count(truths.size(), "truth", "truths") + " x " : std::string()) +
           count(std::size_t(subjects), "subject", "subjects") + " x " + count(protocols.size(), "protocol", "protocols") +
           " x " + count(noiseLevels.size(), "noise level", "noise levels") + " x " +
           count(methods.size(), "method", "methods") + ")";
}

void checkStudyFitsOnDisk(const Study& study, long tasksToCompute, const std::string& outputFolder) {
    namespace fs = std::filesystem;
    fs::path at = fs::absolute(outputFolder.empty() ? "." : outputFolder);
    std::error_code ec;
    while (!fs::exists(at, ec) && at.has_parent_path() && at != at.parent_path()) at = at.parent_path();
    const fs::space_info space = fs::space(at, ec);
    if (ec || space.capacity == 0) return;   // a file system that does not say (sysfs: 0 of 0): nothing to check against
    const double need = double(tasksToCompute) * kStudyBytesPerTask;
    if (need > double(space.available))
        throw InputError("study '" + study.name + "': " + study.describeSize() + ", " + std::to_string(tasksToCompute) +
                         " to compute, need about " + formatBytes(need) + " for the journal and " +
                         "results (" + fmt::format("{:.0f}", kStudyBytesPerTask) + " B a task); " + at.string() +
                         " has " + formatBytes(double(space.available)) + " free: expected a smaller study (subjects, noise levels, methods) or more space");
}

}  // namespace armsim
