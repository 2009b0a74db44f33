#include "model/model_file.h"

#include "basics/files.h"
#include "basics/format.h"
#include "basics/param_node.h"
#include "model/muscle_arm.h"
#include "muscles/muscle_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <regex>

namespace armsim {

const char* getMuscleGroupName(MuscleGroup g) {
    return g == MuscleGroup::Flexor ? "flexor" : g == MuscleGroup::Extensor ? "extensor" : "forearm";
}
const char* getEffortName(Effort e) {
    switch (e) {
        case Effort::Flexion: return "flexion";
        case Effort::Extension: return "extension";
        case Effort::Supination: return "supination";
        case Effort::Pronation: return "pronation";
    }
    return "?";
}
Effort parseEffortName(const std::string& name) {
    for (Effort e : kEfforts)
        if (name == getEffortName(e)) return e;
    throw InputError("effort = '" + name + "': expected flexion, extension, supination or pronation");
}
const char* getArmBodyName(ArmBody b) {
    return b == ArmBody::UpperArm ? "upper_arm" : b == ArmBody::Forearm ? "forearm" : "radius";
}

void SubjectEffort::validate() const {
    checkField("subject.voluntary_activation", voluntaryActivation, Bound{0, 1, true, false});
    checkField("subject.co_contraction", coContraction, Bound::closed(0, 1));
    checkField("subject.trial_cv", trialCv, Bound::closed(0, 0.5));
    checkField("subject.fatigue", fatigue, Bound{0, 1, false, true, "fraction of effort lost per repetition"});
}

int ArmSetup::findMuscle(const std::string& muscleName) const {
    std::string names;
    for (int i = 0; i < getNumMuscles(); ++i) {
        if (muscles[i].params.name == muscleName) return i;
        names += (i ? ", " : "") + muscles[i].params.name;
    }
    throw InputError("model '" + name + "' has no muscle '" + muscleName + "' (muscles: " + names + ")");
}

MuscleParameters ArmSetup::calcMuscleParameters(int i) const {
    MuscleParameters p = muscles.at(i).params;
    p.validate();
    return p;
}

std::shared_ptr<const MuscleModel> buildMuscleModel(const MuscleSpec& m) {
    return findMuscleModelType(m.muscleModel).build(MuscleModelInput{m.params, m.muscleModelCoefficients});
}

std::shared_ptr<const MuscleModel> ArmSetup::buildMuscleModel(int i) const {
    const MuscleSpec& m = muscles.at(i);
    return findMuscleModelType(m.muscleModel).build(MuscleModelInput{calcMuscleParameters(i), m.muscleModelCoefficients});
}

bool ArmSetup::hasOnlyVirtualMuscles() const {
    for (const MuscleSpec& m : muscles)
        if (m.muscleModel != kDefaultMuscleModel) return false;
    return true;
}

void ArmSetup::requireVirtualMuscles(const std::string& what, int i) const {
    for (int k = 0; k < getNumMuscles(); ++k) {
        if ((i >= 0 && k != i) || muscles[k].muscleModel == kDefaultMuscleModel) continue;
        throw InputError(what + " model muscle '" + muscles[k].params.name + "' as a Virtual Muscle, but model '" + name +
                         "' gives it muscle_model " + muscles[k].muscleModel +
                         ": expected virtual_muscle (a truth with Hill-type muscles goes in the truth population)");
    }
}

void ArmSetup::validate() const {
    arm.validate();
    effort.validate();
    if (muscles.empty()) throw InputError("model '" + name + "': no muscles");
    if (primary < 0 || primary >= getNumMuscles())
        throw InputError("model '" + name + "': primary muscle index " + std::to_string(primary) + " out of range");
    for (int i = 0; i < getNumMuscles(); ++i) {
        for (int j = 0; j < i; ++j)
            if (muscles[i].params.name == muscles[j].params.name)
                throw InputError("model '" + name + "': two muscles are called '" + muscles[i].params.name + "'");
        muscles[i].params.validate();
    }
}

ArmSetup ArmSetup::loadDefault() { return loadModel("thesis"); }

namespace {
struct MuscleModelChoice {
    std::string name;
    std::map<std::string, double> coefficients;
};
MuscleModelChoice readMuscleModelChoice(const ParamNode& n, const std::string& inherited);
}  // namespace

void readMuscleModelKey(const ParamNode& node, ArmSetup& setup) {
    const MuscleModelChoice c = readMuscleModelChoice(node, kDefaultMuscleModel);
    node.rethrowWithLocation([&] {
        try {
            setMuscleModel(setup, c.name, c.coefficients);
        } catch (const FieldError&) {
            throw;
        } catch (const InputError& e) {
            throw InputError(node.where("muscle_model") + ": " + e.what());
        }
    });
}

namespace {
std::map<std::string, double> loadMuscleModelCoefficients(const MuscleModelType& type);
}  // namespace

void setMuscleModel(ArmSetup& setup, const std::string& name, const std::map<std::string, double>& coefficients) {
    const MuscleModelType& type = findMuscleModelType(name);
    std::map<std::string, double> c = loadMuscleModelCoefficients(type);
    for (const auto& [k, v] : coefficients) {
        if (std::find(type.coefficientKeys.begin(), type.coefficientKeys.end(), k) == type.coefficientKeys.end())
            throw InputError("muscle model " + name + " has no coefficient '" + k + "'");
        c[k] = v;
    }
    for (MuscleSpec& m : setup.muscles) {
        m.muscleModel = name;
        m.muscleModelCoefficients = c;
    }
    for (int i = 0; i < setup.getNumMuscles(); ++i) setup.buildMuscleModel(i);  // validates
}

namespace {

// A model file's `muscle_model:` (at the top or in a muscle): a registry name, or a mapping with an
// optional `model:` and coefficients of that model (or of `inherited` when it names none).
MuscleModelChoice readMuscleModelChoice(const ParamNode& n, const std::string& inherited) {
    MuscleModelChoice c{inherited, {}};
    auto findType = [&](const ParamNode& node, const std::string& key, const std::string& name) -> const MuscleModelType& {
        try {
            return findMuscleModelType(name);
        } catch (const InputError& e) {
            throw InputError(node.where(key) + ": field " + describeField(node.path(key)) + " = '" + name + "': " +
                             std::string(e.what()).substr(std::string(e.what()).find("expected")));
        }
    };
    if (!n.isMapping("muscle_model")) {
        c.name = n.getString("muscle_model");
        findType(n, "muscle_model", c.name);
        return c;
    }
    const ParamNode m = n.child("muscle_model");
    if (m.has("model")) c.name = m.getString("model");
    const MuscleModelType& type = findType(m, "model", c.name);
    for (const std::string& key : m.getKeys()) {
        if (key == "model") continue;
        if (std::find(type.coefficientKeys.begin(), type.coefficientKeys.end(), key) == type.coefficientKeys.end()) {
            std::string keys;
            for (const std::string& k : type.coefficientKeys) keys += (keys.empty() ? "" : ", ") + k;
            throw InputError(m.where(key) + ": field " + describeField(m.path(key)) + ": muscle model " + type.name +
                             " has no such coefficient (expected " + (keys.empty() ? "none" : "one of " + keys) + ")");
        }
        c.coefficients[key] = m.getNumber(key, Bound::any());
    }
    m.finish();
    return c;
}

// The shipped coefficients of a muscle model (assets/muscles/<file>), as numbers by key.
std::map<std::string, double> loadMuscleModelCoefficients(const MuscleModelType& type) {
    std::map<std::string, double> out;
    if (type.coefficientFile.empty()) return out;
    const ParamNode f = ParamNode::loadFile(findAsset("muscles/" + type.coefficientFile));
    f.getString("source", "");
    for (const std::string& key : type.coefficientKeys) out[key] = f.getNumber(key, Bound::any());
    f.finish();
    return out;
}

std::array<double, 3> readVec3(const ParamNode& n, const std::string& key, const Bound& bound) {
    const std::vector<double> v = n.getNumbers(key, bound);
    if (v.size() != 3)
        throw InputError(n.where(key) + ": field " + describeField(n.path(key)) + " has " + std::to_string(v.size()) +
                         " numbers: expected 3 (x, y, z in the body frame, m)");
    return {v[0], v[1], v[2]};
}

ArmBody readBody(const ParamNode& n) {
    const std::string b = n.getChoice("body", {"upper_arm", "forearm", "radius"}, "");
    return b == "upper_arm" ? ArmBody::UpperArm : b == "forearm" ? ArmBody::Forearm : ArmBody::Radius;
}

PathElementSpec readPoint(const ParamNode& n, const std::string& label, bool via = false) {
    PathElementSpec e;
    e.body = readBody(n);
    e.location = readVec3(n, "location", Bound::closed(-2, 2, "m"));
    e.label = label;
    if (via && n.has("active_rotation_deg")) {
        const std::vector<double> r = n.getNumbers("active_rotation_deg", Bound::closed(-180, 180, "deg"));
        if (r.size() != 2 || !(r[0] < r[1]))
            throw InputError(n.where("active_rotation_deg") + ": field " + describeField(n.path("active_rotation_deg")) +
                             " = " + formatList(r) + ": expected [min, max] with min < max (forearm rotation, deg)");
        e.activeRotationDeg = {r[0], r[1]};
    }
    n.finish();
    return e;
}

PathElementSpec readViaElement(const ParamNode& n, int index) {
    const bool cylinder = n.has("cylinder"), sphere = n.has("sphere");
    if (!cylinder && !sphere) return readPoint(n, "via " + std::to_string(index + 1), true);
    if ((cylinder && sphere) || n.has("location"))
        throw InputError(n.where() + ": via element '" + n.path("") +
                         "' must be one of: a point (location), a cylinder or a sphere");
    PathElementSpec e;
    e.body = readBody(n);
    const ParamNode s = n.child(cylinder ? "cylinder" : "sphere");
    e.kind = cylinder ? PathElementSpec::Kind::Cylinder : PathElementSpec::Kind::Sphere;
    e.location = readVec3(s, "centre", Bound::closed(-2, 2, "m"));
    e.radius = s.getNumber("radius", Bound{0, 0.5, true, false, "m"});
    if (cylinder) {
        e.axis = readVec3(s, "axis", Bound::closed(-1e3, 1e3));
        if (std::hypot(e.axis[0], e.axis[1], e.axis[2]) < 1e-9)
            throw InputError(s.where("axis") + ": field " + describeField(s.path("axis")) + " is the zero vector: expected a direction");
    }
    s.finish();
    if (n.has("side")) {
        e.side = readVec3(n, "side", Bound::closed(-1e3, 1e3));
        if (e.side[0] == 0 && e.side[1] == 0 && e.side[2] == 0)   // no side: it would be ignored
            throw InputError(n.where("side") + ": field " + describeField(n.path("side")) + " is the zero vector: expected a direction");
    }
    if (n.has("winds")) {
        e.winds = n.getBool("winds", false);
        if (e.winds && !n.has("side"))
            throw InputError(n.where("winds") + ": field " + describeField(n.path("winds")) +
                             " = true needs a 'side': the path winds round that side of the surface");
    }
    e.label = std::string(cylinder ? "cylinder " : "sphere ") + std::to_string(index + 1);
    n.finish();
    return e;
}

MuscleSpec readMuscle(const ParamNode& n, const MuscleDefaults& defaults, const MuscleModelChoice& model) {
    MuscleSpec m;
    m.muscleModel = model.name;
    m.muscleModelCoefficients = model.coefficients;
    if (n.has("muscle_model")) {
        const MuscleModelChoice own = readMuscleModelChoice(n, model.name);
        if (own.name != model.name) {
            m.muscleModel = own.name;
            m.muscleModelCoefficients.clear();
        }
        if (m.muscleModelCoefficients.empty() && m.muscleModel != kDefaultMuscleModel)
            m.muscleModelCoefficients = loadMuscleModelCoefficients(findMuscleModelType(m.muscleModel));
        for (const auto& [k, v] : own.coefficients) m.muscleModelCoefficients[k] = v;
    }
    const std::string name = n.getString("name");
    if (!std::regex_match(name, std::regex("[A-Za-z][A-Za-z0-9_]*")))
        throw InputError(n.where("name") + ": field " + describeField(n.path("name")) + " = '" + name +
                         "': expected a name of letters, digits and _ (it names CSV columns)");
    m.source = n.getString("source", "");
    const std::string group = n.getChoice("group", {"flexor", "extensor", "forearm"}, "flexor");
    m.group = group == "flexor" ? MuscleGroup::Flexor : group == "extensor" ? MuscleGroup::Extensor : MuscleGroup::Forearm;
    const bool fromFile = n.has("parameters");
    if (fromFile) {
        m.params = loadMuscleParameters(n.findFile("parameters", "muscle file"), defaults);
    } else {
        auto require = [&](const char* key, const char* alternative) {
            if (n.has(key) || (alternative && n.has(alternative))) return;
            throw InputError(n.where() + ": muscle '" + name + "' needs '" + n.path(key) + "'" +
                             (alternative ? std::string(" or '") + n.path(alternative) + "'" : std::string()) +
                             " (or a 'parameters' muscle file)");
        };
        if (!n.has("volume")) require("mass", "max_isometric_force");
        require("optimal_fascicle_length", nullptr);
        require("optimal_tendon_length", "tendon_slack_length");
        require("fibre_fractions", nullptr);
        require("fibre_types", nullptr);
    }
    readMuscleFields(n, m.params, false, defaults);
    m.maxPathFromRange = !n.has("max_path_length");
    m.params.name = name;
    m.sourceParams = m.params;
    if (n.has("calibration")) {
        const ParamNode c = n.child("calibration");
        const Bound scale = Bound::closed(0.2, 5);
        MuscleCalibration cal;
        cal.forceScale = c.getNumber("force_scale", scale, 1.0);
        cal.fascicleLengthScale = c.getNumber("fascicle_length_scale", scale, 1.0);
        cal.tendonLengthScale = c.getNumber("tendon_length_scale", scale, 1.0);
        cal.specificTensionScale = c.getNumber("specific_tension_scale", scale, 1.0);
        c.getString("source", "");
        c.finish();
        m.setCalibration(cal);
    }

    const ParamNode path = n.child("path");
    m.path.push_back(readPoint(path.child("origin"), "origin"));
    if (path.has("via")) {
        const std::vector<ParamNode> via = path.children("via");
        for (int i = 0; i < int(via.size()); ++i) m.path.push_back(readViaElement(via[i], i));
    }
    m.path.push_back(readPoint(path.child("insertion"), "insertion"));
    path.finish();
    if (std::all_of(m.path.begin(), m.path.end(), [&](const PathElementSpec& e) { return e.body == m.path[0].body; }))
        throw InputError(path.where("insertion") + ": muscle '" + name + "': its origin, insertion and every via point are on the " +
                         getArmBodyName(m.path[0].body) + ": expected a path that crosses a joint (one on a single body "
                         "keeps its length, and has no moment arm, in every posture)");
    for (std::size_t k = 1; k + 1 < m.path.size(); ++k)
        if (m.path[k].kind != PathElementSpec::Kind::Point && m.path[k + 1].kind != PathElementSpec::Kind::Point)
            throw InputError(path.where("via") + ": muscle '" + name + "': wrapping surfaces '" + m.path[k].label +
                             "' and '" + m.path[k + 1].label +
                             "' follow each other: put a via point between them (one surface between two points)");
    n.finish();
    if (!m.maxPathFromRange) n.rethrowWithLocation([&] { m.params.validate(); });
    return m;
}

// roles.synergists: flexors (an extensor would be fitted to flexion torque), none of them a biceps head
// (a head fitted twice).
void checkSynergistRoles(const ArmSetup& s, const ParamNode& roles) {
    const std::vector<int> heads = s.getBicepsHeads();   // the primary alone when roles.biceps is absent
    for (int m : s.synergists) {
        if (s.muscles[m].group != MuscleGroup::Flexor)
            throw InputError(roles.where("synergists") + ": field 'roles.synergists' lists '" + s.muscles[m].params.name +
                             "', of group " + getMuscleGroupName(s.muscles[m].group) +
                             ": expected the biceps heads' synergists, flexors");
        if (std::find(heads.begin(), heads.end(), m) != heads.end())
            throw InputError(roles.where("synergists") + ": field 'roles.synergists' lists '" +
                             s.muscles[m].params.name + "', a biceps head (roles.biceps, or the primary): expected the biceps heads' "
                             "synergists (the other flexors), each muscle in one role");
    }
}

// Every muscle whose P_max is its longest path over the range has a steady state there, at rest and at
// full drive (the longest fascicle any posture asks of it); a path lengthened by a misplaced point or a wrapping
// surface's reversed side has none, and would fail the first trial that reaches that posture.
void checkSteadyStatesAtLongestPaths(const ArmSetup& s, const std::string& file) {
    for (int i = 0; i < s.getNumMuscles(); ++i) {
        if (!s.muscles[i].maxPathFromRange) continue;
        const double P = s.muscles[i].params.maxPathLength;
        const std::shared_ptr<const MuscleModel> muscle = s.buildMuscleModel(i);
        for (double U : {0.0, 1.0}) {
            const SteadyState steady = muscle->calcSteadyState(P, U);
            if (!steady.converged)
                throw InputError(file + ": muscle '" + s.muscles[i].params.name + "': its path over the elbow's range reaches " +
                                 formatNumber(P, 6) + " m, where it has no steady state at activation " +
                                 formatNumber(U) + " (" + steady.message + "): expected a path the muscle can span (a "
                                 "misplaced via point, or a wrapping surface's side reversed, lengthens it)");
        }
    }
}

// The primary and roles.biceps: the thesis's biceps, a flexor (an extensor head would be an antagonist
// in every flexion effort).
void checkBicepsHeadsAreFlexors(const ArmSetup& s, const std::vector<ParamNode>& muscleNodes) {
    for (int m : s.getBicepsHeads())
        if (s.muscles[m].group != MuscleGroup::Flexor) {
            const ParamNode& n = muscleNodes[std::size_t(m)];
            throw InputError((n.has("group") ? n.where("group") : n.where()) + ": muscle '" + s.muscles[m].params.name +
                             "' is the " + (m == s.primary ? "primary muscle" : "biceps head") + " but of group " +
                             getMuscleGroupName(s.muscles[m].group) +
                             ": expected a flexor (the biceps the identifiers and the thesis's estimate stand for)");
        }
}

// The thesis's A and B for a model without a `biceps` section: the primary muscle's origin and
// insertion distances from the elbow centre.
void deriveThesisGeometry(ArmSetup& s) {
    const std::vector<PathElementSpec>& path = s.muscles[s.primary].path;
    const auto& o = path.front().location;
    const auto& i = path.back().location;
    s.arm.originDistance = std::hypot(o[0], o[1], o[2]);
    s.arm.insertionDistance = std::hypot(i[0], i[1], i[2]);
}

}  // namespace

void MuscleCalibration::validate() const {
    const Bound scale = Bound::closed(0.2, 5);
    checkField("calibration.force_scale", forceScale, scale);
    checkField("calibration.fascicle_length_scale", fascicleLengthScale, scale);
    checkField("calibration.tendon_length_scale", tendonLengthScale, scale);
    checkField("calibration.specific_tension_scale", specificTensionScale, scale);
}

void MuscleSpec::setCalibration(const MuscleCalibration& c) {
    c.validate();
    calibration = c;
    const double maxPath = params.maxPathLength;
    params = sourceParams;
    params.maxPathLength = maxPath;
    params.optimalFascicleLength *= c.fascicleLengthScale;
    params.mass *= c.forceScale * c.fascicleLengthScale;
    params.optimalTendonLength *= c.tendonLengthScale;
    params.coefficients.sigma *= c.specificTensionScale;
}

ArmSetup applyCalibration(const ArmSetup& setup, const std::vector<MuscleCalibration>& calibration) {
    if (calibration.size() != setup.muscles.size())
        throw std::logic_error("applyCalibration: " + std::to_string(calibration.size()) + " calibrations for " +
                               std::to_string(setup.muscles.size()) + " muscles");
    ArmSetup s = setup;
    for (std::size_t i = 0; i < s.muscles.size(); ++i) s.muscles[i].setCalibration(calibration[i]);
    return s;
}

std::vector<std::string> listModels() {
    std::vector<std::string> names;
    const std::filesystem::path dir = std::filesystem::path(getAssetDirectory()) / "models";
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec))
        if (e.path().extension() == ".yaml") names.push_back(e.path().stem().string());
    std::sort(names.begin(), names.end());
    return names;
}

namespace {
ArmSetup loadModelFile(const std::string& file);
constexpr std::size_t kModelCacheSize = 32;  ///< distinct model files kept (then the cache starts over)
constexpr std::size_t kModelCacheBytes = 4 << 20;  ///< a model whose files hold more is not kept
}  // namespace

ArmSetup loadModel(const std::string& nameOrFile) {
    std::string file = nameOrFile;
    const bool looksLikeName = nameOrFile.find('/') == std::string::npos &&
                               nameOrFile.find(".yaml") == std::string::npos;
    const std::string osimNote = "an OpenSim model: `armsim forward`, `armsim trial`, `armsim model show`, `armsim model check`, "
                                 "`armsim render`, torque protocols (subject.model) and Python's armsim.forward, "
                                 "armsim.isometric_trial, armsim.free_movement and run_protocol take .osim files; "
                                 "this command takes an armsim model file (.yaml) yet";
    if (looksLikeName) {
        const std::string asset = getAssetDirectory() + "/models/" + nameOrFile + ".yaml";
        if (!doesPathExist(asset)) {
            if (doesPathExist(getAssetDirectory() + "/models/" + nameOrFile + ".osim"))
                throw InputError("--model '" + nameOrFile + "': assets/models/" + nameOrFile + ".osim is " + osimNote);
            std::string known, osim;
            for (const std::string& m : listModels()) known += (known.empty() ? "" : ", ") + m;
            std::error_code ec;
            for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(getAssetDirectory()) / "models", ec))
                if (e.path().extension() == ".osim") osim += (osim.empty() ? "" : ", ") + e.path().stem().string();
            throw InputError("--model '" + nameOrFile + "': no such model (shipped models: " + known +
                             (osim.empty() ? std::string() : "; OpenSim models, for forward, trial and model show: " + osim) +
                             "; or give a model file path)");
        }
        file = asset;
    } else if (!doesPathExist(file)) {
        throw InputError(file + ": no such model file");
    }
    if (file.size() > 5 && file.compare(file.size() - 5, 5, ".osim") == 0) throw InputError(file + ": " + osimNote);

    // Loading resolves paths over the elbow's range (a few ms, 40 ms under sanitizers): a model is
    // reused while the model file and every file it read are byte for byte as they were and every
    // file it looked for (a relative reference tried beside the model first) is still there or absent.
    struct CachedModel {
        std::vector<FileSnapshot> files;
        ArmSetup setup;
    };
    static std::mutex cacheMutex;
    static std::map<std::string, std::shared_ptr<const CachedModel>> cache;
    std::error_code ec;
    // The folder with links resolved (link/.. names another file), the name as given: references are
    // looked up beside the path as given, so two links to one file in two folders are two models.
    const std::filesystem::path given(file);
    const std::string real =
        (std::filesystem::weakly_canonical(std::filesystem::absolute(given, ec).parent_path(), ec) / given.filename())
            .string();
    if (ec) return loadModelFile(file);
    const std::string key = getAssetDirectory() + '\n' + real;
    std::shared_ptr<const CachedModel> cached;
    {
        std::lock_guard<std::mutex> lock(cacheMutex);
        const auto it = cache.find(key);
        if (it != cache.end()) cached = it->second;
    }
    if (cached && areFilesUnchanged(cached->files)) {  // the files are read outside the lock
        ArmSetup s = cached->setup;
        s.file = file;
        return s;
    }
    FileReadRecorder recorder;
    ArmSetup s = loadModelFile(file);
    std::size_t bytes = 0;
    for (const FileSnapshot& f : recorder.getFiles()) bytes += f.text.size();
    if (bytes > kModelCacheBytes) return s;
    std::lock_guard<std::mutex> lock(cacheMutex);
    if (cache.size() >= kModelCacheSize) cache.clear();
    cache[key] = std::make_shared<const CachedModel>(CachedModel{recorder.releaseFiles(), s});
    return s;
}

namespace {

ArmSetup loadModelFile(const std::string& file) {
    const ParamNode root = ParamNode::loadFile(file);
    ArmSetup s;
    s.file = file;
    s.name = root.getString("name");
    s.description = root.getString("description", "");
    root.getString("source", "");

    bool hasBiceps = false;
    if (root.isMapping("arm")) {
        const ParamNode arm = root.child("arm");
        arm.getString("source", "");
        hasBiceps = readArmParameters(arm, s.arm, false);
        arm.finish();
    } else {
        s.arm = loadArmParameters(root.findFile("arm", "arm file", getAssetDirectory()));
        hasBiceps = true;
    }

    if (root.has("subject")) {
        const ParamNode subj = root.child("subject");
        const Bound any = Bound::any();
        s.effort.voluntaryActivation = subj.getNumber("voluntary_activation", any, s.effort.voluntaryActivation);
        s.effort.coContraction = subj.getNumber("co_contraction", any, s.effort.coContraction);
        s.effort.trialCv = subj.getNumber("trial_cv", any, s.effort.trialCv);
        s.effort.fatigue = subj.getNumber("fatigue", any, s.effort.fatigue);
        subj.finish();
        subj.rethrowWithLocation([&] { s.effort.validate(); });
    }

    if (root.has("specific_tension"))
        s.specificTension = root.getNumber("specific_tension", getSpecificTensionBound());
    if (root.has("max_firing_rate")) s.maxFiringRate = root.getNumber("max_firing_rate", getMaxFiringRateBound());
    MuscleModelChoice model{kDefaultMuscleModel, {}};
    if (root.has("muscle_model")) {
        model = readMuscleModelChoice(root, kDefaultMuscleModel);
        std::map<std::string, double> c = loadMuscleModelCoefficients(findMuscleModelType(model.name));
        for (const auto& [k, v] : model.coefficients) c[k] = v;
        model.coefficients = c;
    }
    const std::vector<ParamNode> muscleNodes = root.children("muscles");
    for (const ParamNode& m : muscleNodes)
        s.muscles.push_back(readMuscle(m, MuscleDefaults{s.specificTension, s.maxFiringRate}, model));
    if (s.muscles.empty()) throw InputError(root.where("muscles") + ": field 'muscles' is empty: expected at least one muscle");
    if (root.has("primary")) {
        const std::string primary = root.getString("primary");
        try {
            s.primary = s.findMuscle(primary);
        } catch (const InputError& e) {
            throw InputError(root.where("primary") + ": field 'primary' = '" + primary + "': " + e.what());
        }
    }
    if (root.has("roles")) {
        const ParamNode roles = root.child("roles");
        auto read = [&](const char* key) {
            std::vector<int> out;
            for (const std::string& name : roles.getStrings(key)) {
                try {
                    out.push_back(s.findMuscle(name));
                } catch (const InputError& e) {
                    throw InputError(roles.where(key) + ": field " + describeField(roles.path(key)) + ": " + e.what());
                }
                if (std::count(out.begin(), out.end(), out.back()) > 1)
                    throw InputError(roles.where(key) + ": field " + describeField(roles.path(key)) + " lists '" + name +
                                     "' twice: expected each muscle once");
            }
            return out;
        };
        if (roles.has("biceps")) s.bicepsHeads = read("biceps");
        if (roles.has("synergists")) s.synergists = read("synergists");
        checkSynergistRoles(s, roles);
        if (roles.has("surface_emg")) s.surfaceEmg = read("surface_emg");
        roles.finish();
        if (!s.bicepsHeads.empty() && std::find(s.bicepsHeads.begin(), s.bicepsHeads.end(), s.primary) == s.bicepsHeads.end())
            throw InputError(roles.where("biceps") + ": field 'roles.biceps' does not name the primary muscle '" +
                             s.muscles[s.primary].params.name + "': expected it among the biceps heads");
    }
    root.finish();
    checkBicepsHeadsAreFlexors(s, muscleNodes);
    if (!s.arm.forearmRotation.enabled)
        for (const MuscleSpec& m : s.muscles)
            for (const PathElementSpec& e : m.path)
                if (e.body == ArmBody::Radius)
                    throw InputError(file + ": muscle '" + m.params.name + "' " + e.label +
                                     ": body 'radius' needs the arm's forearm_rotation section");
    if (!hasBiceps) deriveThesisGeometry(s);
    // An inline arm's fields are named relative to its mapping ('forearm_rotation.posture_deg').
    (root.isMapping("arm") ? root.child("arm") : root).rethrowWithLocation([&] { s.arm.validate(); });
    resolveMaxPathLengths(s);
    try {
        s.validate();
        for (int i = 0; i < s.getNumMuscles(); ++i)
            if (s.muscles[i].muscleModel != kDefaultMuscleModel) s.buildMuscleModel(i);  // validates its coefficients
    } catch (const InputError& e) {
        throw InputError(file + ": " + e.what());
    }
    checkSteadyStatesAtLongestPaths(s, file);
    return s;
}

}  // namespace
}  // namespace armsim
