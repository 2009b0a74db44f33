#include "basics/param_node.h"

#include "basics/files.h"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

namespace armsim {

struct ParamNode::Impl {
    std::string source;
    std::string prefix;   // dotted path of this mapping
    YAML::Node node;
    std::shared_ptr<std::set<std::string>> used = std::make_shared<std::set<std::string>>();
    std::shared_ptr<std::set<std::string>> asked = std::make_shared<std::set<std::string>>();   // present or not
};

ParamNode::ParamNode(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}
ParamNode::ParamNode(const ParamNode&) = default;
ParamNode& ParamNode::operator=(const ParamNode&) = default;
ParamNode::~ParamNode() = default;

namespace {

constexpr int kMaxDepth = 64;              ///< nesting of mappings and lists (parameter files use a handful)
constexpr long kMaxValues = 1000000;       ///< values with aliases expanded (a few thousand in a protocol)

// Every mapping key is a plain scalar (the readers compare keys as strings) and appears once in its
// mapping (YAML forbids repeats; yaml-cpp would keep the first silently); nesting and the document as
// aliases expand it are bounded (`&a [..]`, `&b [*a, *a, ..]`, ... grows exponentially).
void checkKeysAndSize(const YAML::Node& n, const std::string& source, int depth, long& values) {
    auto where = [&](const YAML::Node& at) { return source + ":" + std::to_string(at.Mark().line + 1); };
    if (depth > kMaxDepth)
        throw InputError(where(n) + ": nested deeper than " + std::to_string(kMaxDepth) +
                         " levels: expected a parameter file");
    if (++values > kMaxValues)
        throw InputError(where(n) + ": more than " + std::to_string(kMaxValues) +
                         " values (with aliases expanded): expected a parameter file");
    if (n.IsMap()) {
        std::map<std::string, int> seen;   // key -> line of its first appearance
        for (auto it = n.begin(); it != n.end(); ++it) {
            if (it->first.IsNull())
                throw InputError(where(it->first) + ": an empty key ('~', 'null' or a bare '?'): expected a name");
            if (!it->first.IsScalar())
                throw InputError(where(it->first) +
                                 ": a key that is a list or mapping ('? ...' or '[...]: ...'): expected a name");
            const auto [first, isNew] = seen.emplace(it->first.Scalar(), it->first.Mark().line + 1);
            if (!isNew)
                throw InputError(where(it->first) + ": key '" + it->first.Scalar() + "' appears again (first at line " +
                                 std::to_string(first->second) + "): expected each key once per mapping");
            checkKeysAndSize(it->second, source, depth + 1, values);
        }
    } else if (n.IsSequence()) {
        for (const YAML::Node& e : n) checkKeysAndSize(e, source, depth + 1, values);
    }
}

/// Notes whether a parsed document holds anything but a null (a bare '---' or a trailing one holds nothing).
class ContentFinder : public YAML::EventHandler {
public:
    bool hasContent = false;
    YAML::Mark start;     ///< where the document starts ('---' or its first token)
    YAML::Mark content;   ///< where its first value starts
    void OnDocumentStart(const YAML::Mark& mark) override { start = mark; }
    void OnDocumentEnd() override {}
    void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
    void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { noteContent(mark); }
    void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string&) override {
        noteContent(mark);
    }
    void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                         YAML::EmitterStyle::value) override {
        noteContent(mark);
    }
    void OnSequenceEnd() override {}
    void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
        noteContent(mark);
    }
    void OnMapEnd() override {}

private:
    void noteContent(const YAML::Mark& mark) {
        if (!hasContent) content = mark;
        hasContent = true;
    }
};

/// Refuses a second document with content, after any number of empty ones. yaml-cpp 0.7's LoadAll never
/// ends on some malformed input (a token no node starts with is never consumed; jbeder/yaml-cpp#1319), so
/// the documents are walked here while each starts past the last: a parse that does not move is that
/// stray token, refused at its line.
void checkSingleDocument(const std::string& text, const std::string& sourceName) {
    std::istringstream in(text);
    YAML::Parser parser(in);
    ContentFinder first;
    if (!parser.HandleNextDocument(first)) return;
    for (int lastStart = first.start.pos;;) {
        ContentFinder next;
        if (!parser.HandleNextDocument(next)) return;
        if (next.start.pos <= lastStart)
            throw InputError(sourceName + ":" + std::to_string(next.start.line + 1) +
                             ": invalid YAML: text no value starts with (a stray ',', ']' or '}'?)");
        if (next.hasContent)
            throw InputError(sourceName + ":" + std::to_string(next.content.line + 1) +
                             ": a second YAML document (after '---'): expected one document per file");
        lastStart = next.start.pos;
    }
}

}  // namespace

ParamNode ParamNode::loadString(const std::string& text, const std::string& sourceName) {
    auto impl = std::make_shared<Impl>();
    impl->source = sourceName;
    try {
        impl->node = YAML::Load(text);
        checkSingleDocument(text, sourceName);   // a second '---' document would never be read
    } catch (const YAML::DeepRecursion& e) {  // yaml-cpp says only "bad file"
        throw InputError(sourceName + ":" + std::to_string(e.mark.line + 1) + ": nested deeper than " +
                         std::to_string(e.depth()) + " levels: expected a parameter file");
    } catch (const YAML::Exception& e) {
        throw InputError(sourceName + ":" + std::to_string(e.mark.line + 1) + ": invalid YAML: " + e.msg);
    }
    if (!impl->node.IsMap())
        throw InputError(sourceName + ":1: expected a mapping of 'key: value' lines at the top level");
    long values = 0;
    checkKeysAndSize(impl->node, sourceName, 0, values);
    return ParamNode(impl);
}

ParamNode ParamNode::loadFile(const std::string& path) { return loadString(readFileText(path), path); }

const YAML::Node& ParamNode::node() const { return impl_->node; }
const std::string& ParamNode::getSourceName() const { return impl_->source; }

std::string ParamNode::getDirectory() const {
    return std::filesystem::path(impl_->source).parent_path().string();
}

std::string ParamNode::findFile(const std::string& key, const std::string& what,
                                const std::string& fallbackDirectory) const {
    const std::string file = getString(key);
    const std::string dir = getDirectory();
    const std::string relative = dir.empty() ? file : dir + "/" + file;
    if (doesPathExist(relative)) return relative;
    if (doesPathExist(file)) return file;
    if (!fallbackDirectory.empty() && doesPathExist(fallbackDirectory + "/" + file))
        return fallbackDirectory + "/" + file;
    throw InputError(where(key) + ": field " + describeField(path(key)) + " = '" + file + "': no such " + what +
                     " (relative paths are taken from the file's directory" +
                     (fallbackDirectory.empty() ? std::string() : " or " + fallbackDirectory) + ")");
}

std::string ParamNode::path(const std::string& key) const {
    if (impl_->prefix.empty()) return key;
    if (key.empty()) return impl_->prefix;
    return impl_->prefix + "." + key;
}

std::string ParamNode::where(const std::string& key) const {
    int line = node().Mark().line;
    if (!key.empty()) {
        for (auto it = node().begin(); it != node().end(); ++it)
            if (it->first.as<std::string>() == key) { line = it->first.Mark().line; break; }
    }
    return impl_->source + ":" + std::to_string(line + 1);
}

bool ParamNode::has(const std::string& key) const {
    impl_->asked->insert(key);
    return bool(node()[key]);
}

YAML::Node ParamNode::requireKey(const std::string& key) const {
    impl_->asked->insert(key);
    YAML::Node n = node()[key];
    if (!n) throw InputError(where() + ": missing required field " + describeField(path(key)));
    impl_->used->insert(key);
    return n;
}

ParamNode ParamNode::child(const std::string& key) const {
    YAML::Node n = requireKey(key);
    if (!n.IsMap()) throw InputError(where(key) + ": field " + describeField(path(key)) + " must be a mapping");
    auto impl = std::make_shared<Impl>();
    impl->source = impl_->source;
    impl->prefix = path(key);
    impl->node = n;
    return ParamNode(impl);
}

std::vector<ParamNode> ParamNode::children(const std::string& key) const {
    YAML::Node n = requireKey(key);
    if (!n.IsSequence()) throw InputError(where(key) + ": field " + describeField(path(key)) + " must be a list");
    std::vector<ParamNode> out;
    for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string item = path(key) + "[" + std::to_string(i) + "]";
        if (!n[i].IsMap())
            throw InputError(impl_->source + ":" + std::to_string(n[i].Mark().line + 1) + ": field " + describeField(item) +
                             " must be a mapping");
        auto impl = std::make_shared<Impl>();
        impl->source = impl_->source;
        impl->prefix = item;
        impl->node = n[i];
        out.push_back(ParamNode(impl));
    }
    return out;
}

bool ParamNode::isMapping(const std::string& key) const {
    const YAML::Node n = node()[key];
    return n && n.IsMap();
}

static double toNumber(const YAML::Node& n, const std::string& where, const std::string& field) {
    if (!n.IsScalar()) throw InputError(where + ": field " + describeField(field) + " must be a number");
    try {
        return n.as<double>();
    } catch (const YAML::Exception&) {
        throw InputError(where + ": field " + describeField(field) + " = '" + n.Scalar() + "': expected a number");
    }
}

double ParamNode::getNumber(const std::string& key, const Bound& bound) const {
    double v = toNumber(requireKey(key), where(key), path(key));
    try {
        checkField(path(key), v, bound);
    } catch (const FieldError& e) {
        throw InputError(where(key) + ": " + e.what());
    }
    return v;
}

double ParamNode::getNumber(const std::string& key, const Bound& bound, double defaultValue) const {
    return has(key) ? getNumber(key, bound) : defaultValue;
}

int ParamNode::getInt(const std::string& key, int lo, int hi) const {
    double v = getNumber(key, Bound::closed(lo, hi));
    if (v != std::floor(v))
        throw InputError(where(key) + ": field " + describeField(path(key)) + " = " + formatNumber(v) +
                         ": expected a whole number");
    return int(v);
}

int ParamNode::getInt(const std::string& key, int lo, int hi, int defaultValue) const {
    return has(key) ? getInt(key, lo, hi) : defaultValue;
}

bool ParamNode::getBool(const std::string& key, bool defaultValue) const {
    if (!has(key)) return defaultValue;
    YAML::Node n = requireKey(key);
    try {
        return n.as<bool>();
    } catch (const YAML::Exception&) {
        throw InputError(where(key) + ": field " + describeField(path(key)) + " = '" + n.Scalar() +
                         "': expected true or false");
    }
}

std::string ParamNode::getString(const std::string& key) const {
    YAML::Node n = requireKey(key);
    if (!n.IsScalar()) throw InputError(where(key) + ": field " + describeField(path(key)) + " must be a string");
    return n.Scalar();
}

std::string ParamNode::getString(const std::string& key, const std::string& defaultValue) const {
    return has(key) ? getString(key) : defaultValue;
}

std::string ParamNode::getChoice(const std::string& key, const std::vector<std::string>& allowed,
                                 const std::string& defaultValue) const {
    std::string v = getString(key, defaultValue);
    for (const auto& a : allowed)
        if (a == v) return v;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw InputError(where(key) + ": field " + describeField(path(key)) + " = '" + v + "': expected one of " + list);
}

std::vector<double> ParamNode::getNumbers(const std::string& key, const Bound& bound) const {
    YAML::Node n = requireKey(key);
    if (!n.IsSequence())
        throw InputError(where(key) + ": field " + describeField(path(key)) + " must be a list of numbers");
    std::vector<double> out;
    for (std::size_t i = 0; i < n.size(); ++i) {
        const std::string field = path(key) + "[" + std::to_string(i) + "]";
        const std::string at = impl_->source + ":" + std::to_string(n[i].Mark().line + 1);
        double v = toNumber(n[i], at, field);
        try {
            checkField(field, v, bound);
        } catch (const FieldError& e) {
            throw InputError(at + ": " + e.what());
        }
        out.push_back(v);
    }
    return out;
}

std::vector<std::string> ParamNode::getStrings(const std::string& key) const {
    YAML::Node n = requireKey(key);
    if (!n.IsSequence()) throw InputError(where(key) + ": field " + describeField(path(key)) + " must be a list of strings");
    std::vector<std::string> out;
    for (std::size_t i = 0; i < n.size(); ++i) {
        if (!n[i].IsScalar() || n[i].Scalar().empty())
            throw InputError(impl_->source + ":" + std::to_string(n[i].Mark().line + 1) + ": field " +
                             describeField(path(key) + "[" + std::to_string(i) + "]") + " must be a non-empty string");
        out.push_back(n[i].Scalar());
    }
    return out;
}

std::vector<std::string> ParamNode::getKeys() const {
    std::vector<std::string> keys;
    for (auto it = node().begin(); it != node().end(); ++it) keys.push_back(it->first.as<std::string>());
    return keys;
}

void ParamNode::finish() const {
    for (auto it = node().begin(); it != node().end(); ++it) {
        const std::string key = it->first.as<std::string>();
        if (!impl_->used->count(key)) {
            std::string fields;   // what the reader asked for here
            for (const std::string& k : *impl_->asked) fields += (fields.empty() ? "" : ", ") + k;
            throw InputError(impl_->source + ":" + std::to_string(it->first.Mark().line + 1) +
                             ": unknown field " + describeField(path(key)) + " (misspelt, or not a field here)" +
                             (fields.empty() ? std::string() : ": expected one of " + fields));
        }
    }
}

void ParamNode::throwLocated(const FieldError& e) const {
    // Walk the dotted field path as far as the file has it, and report that line.
    std::string field = e.getField();
    if (!impl_->prefix.empty() && field.rfind(impl_->prefix + ".", 0) == 0)
        field = field.substr(impl_->prefix.size() + 1);
    YAML::Node n = node();
    int line = n.Mark().line;
    std::stringstream parts(field);
    std::string part;
    while (std::getline(parts, part, '.')) {
        // "conditions[2]": the key, then entry 2 of its list.
        std::size_t index = std::string::npos;
        const std::size_t open = part.find('[');
        if (open != std::string::npos && part.back() == ']') {
            try {
                index = std::stoul(part.substr(open + 1, part.size() - open - 2));
            } catch (const std::exception&) {
                index = std::string::npos;
            }
            part = part.substr(0, open);
        }
        if (!n.IsMap()) break;
        bool found = false;
        for (auto it = n.begin(); it != n.end(); ++it)
            if (it->first.as<std::string>() == part) {
                line = it->first.Mark().line;
                n.reset(it->second);   // rebind the handle (operator= would overwrite the document's node)
                found = true;
                break;
            }
        if (!found) break;
        if (index != std::string::npos) {
            if (!n.IsSequence() || index >= n.size()) break;
            const YAML::Node entry = n[index];
            n.reset(entry);
            line = n.Mark().line;
        }
    }
    throw InputError(impl_->source + ":" + std::to_string(line + 1) + ": field " + describeField(path(field)) + " " +
                     e.getDetail());
}


}  // namespace armsim
