#include "multicue/io/config.hpp"

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/core/logging.hpp"
#include "multicue/io/file_utils.hpp"
#include "multicue/io/json_text.hpp"

namespace multicue::io {

struct ConfigSection::State {
    std::string source;
    nlohmann::json root = nlohmann::json::object();
    std::set<std::string> used;  // full key paths asked for
    nlohmann::ordered_json defaults = nlohmann::ordered_json::object();
    std::vector<std::pair<std::string, std::string>> help;  // full key path -> help text
};

namespace {

std::string Join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
}

void WriteDump(const nlohmann::ordered_json& j, const std::string& path,
               const std::vector<std::pair<std::string, std::string>>& help, int indent,
               std::string& out) {
    const std::string pad(static_cast<std::size_t>(indent) * 2, ' ');
    out += "{\n";
    std::size_t k = 0;
    for (auto it = j.begin(); it != j.end(); ++it, ++k) {
        const std::string full = Join(path, it.key());
        for (const auto& [p, text] : help) {
            if (p == full && !text.empty()) out += pad + "  // " + text + "\n";
        }
        out += pad + "  " + nlohmann::json(it.key()).dump() + ": ";
        if (it.value().is_object()) {
            WriteDump(it.value(), full, help, indent + 1, out);
        } else {
            out += it.value().dump();
        }
        out += (k + 1 < j.size() ? ",\n" : "\n");
    }
    out += pad + "}";
}

// The object at a dotted path below `root`, or null.
nlohmann::json* Find(nlohmann::json& root, const std::string& path) {
    nlohmann::json* node = &root;
    std::size_t start = 0;
    while (true) {
        const std::size_t dot = path.find('.', start);
        const std::string part = path.substr(start, dot == std::string::npos ? dot : dot - start);
        if (!node->is_object() || !node->contains(part)) return nullptr;
        node = &(*node)[part];
        if (dot == std::string::npos) return node;
        start = dot + 1;
    }
}

// The value at a dotted path below `root`, with the sections on the way created; null when a
// value on the way is not a section.
template <typename Json>
Json* Create(Json& root, const std::string& path) {
    Json* node = &root;
    std::size_t start = 0;
    while (true) {
        if (!node->is_null() && !node->is_object()) return nullptr;
        const std::size_t dot = path.find('.', start);
        node = &(*node)[path.substr(start, dot == std::string::npos ? dot : dot - start)];
        if (dot == std::string::npos) return node;
        start = dot + 1;
    }
}

void CheckUsed(const nlohmann::json& j, const std::string& path, const std::set<std::string>& used,
               const std::string& source) {
    for (auto it = j.begin(); it != j.end(); ++it) {
        const std::string full = Join(path, it.key());
        if (!used.count(full)) {
            throw InvalidArgument(fmt::format("{}: unknown key '{}'", source, full));
        }
        if (it.value().is_object()) CheckUsed(it.value(), full, used, source);
    }
}

}  // namespace

ConfigSection::ConfigSection(std::shared_ptr<State> state, std::string path)
    : state_(std::move(state)), path_(std::move(path)) {}

ConfigSection ConfigSection::Parse(const std::string& text, const std::string& source) {
    auto state = std::make_shared<State>();
    state->source = source;
    try {
        state->root = ParseJsonText(text, source, {.allow_comments = true});
    } catch (const FormatError& e) {
        // A parameter file is an argument: a bad one is a usage error (exit code 2).
        throw InvalidArgument(e.what());
    }
    if (!state->root.is_object()) {
        throw InvalidArgument(fmt::format("{}: expected a JSON object at the top level", source));
    }
    return ConfigSection(std::move(state), "");
}

ConfigSection ConfigSection::Load(const std::filesystem::path& path) {
    return Parse(ReadFileBytes(path), path.string());
}

ConfigSection ConfigSection::Dump() {
    auto state = std::make_shared<State>();
    state->source = "defaults";
    return ConfigSection(std::move(state), "");
}

const nlohmann::json* ConfigSection::Lookup(const std::string& key) {
    const std::string full = Join(path_, key);
    const nlohmann::json* node = Find(state_->root, full);
    if (node != nullptr) state_->used.insert(full);
    return node;
}

void ConfigSection::Record(const std::string& key, nlohmann::json value, const std::string& help) {
    const std::string full = Join(path_, key);
    *Create(state_->defaults, full) = nlohmann::ordered_json(value);
    state_->help.emplace_back(full, help);
}

nlohmann::json ConfigSection::FloatToJson(float value) {
    return std::stod(fmt::format("{}", value));
}

void ConfigSection::TypeError(const std::string& key, const char* expected) const {
    throw InvalidArgument(
        fmt::format("{}: '{}' must be {}", state_->source, Join(path_, key), expected));
}

void ConfigSection::Get(const std::string& key, Eigen::Vector3f& value, const std::string& help) {
    if (const nlohmann::json* j = Lookup(key)) {
        const auto is_float = [](const nlohmann::json& x) {
            return x.is_number() && std::abs(x.get<double>()) <= std::numeric_limits<float>::max();
        };
        if (!j->is_array() || j->size() != 3 || !is_float((*j)[0]) || !is_float((*j)[1]) ||
            !is_float((*j)[2])) {
            TypeError(key, "an array of three finite numbers");
        }
        value = Eigen::Vector3f((*j)[0].get<float>(), (*j)[1].get<float>(), (*j)[2].get<float>());
    } else {
        Record(key,
               nlohmann::json::array(
                   {FloatToJson(value.x()), FloatToJson(value.y()), FloatToJson(value.z())}),
               help);
    }
}

void ConfigSection::Get(const std::string& key, std::optional<Eigen::Vector3f>& value,
                        const std::string& help) {
    if (const nlohmann::json* j = Lookup(key)) {
        if (j->is_null()) {
            value.reset();
            return;
        }
        Eigen::Vector3f v = Eigen::Vector3f::Zero();
        Get(key, v, help);
        value = v;
    } else if (value) {
        Get(key, *value, help);
    } else {
        Record(key, nullptr, help);
    }
}

void ConfigSection::GetChoice(const std::string& key, std::string& value,
                              std::span<const std::string_view> choices, const std::string& help) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + std::string(c);
    if (Lookup(key) == nullptr) {
        Record(key, value, help.empty() ? "one of " + list : help + " (" + list + ")");
        return;
    }
    Get(key, value, help);
    for (const auto& c : choices) {
        if (c == value) return;
    }
    throw InvalidArgument(fmt::format("{}: '{}' must be one of {}, got '{}'", state_->source,
                                      Join(path_, key), list, value));
}

namespace {

// Moves `from` into `into`: values are set, sections merged; false when a value is in both.
bool MergeInto(nlohmann::json& into, nlohmann::json&& from) {
    if (!into.is_object() || !from.is_object()) return false;
    for (auto it = from.begin(); it != from.end(); ++it) {
        if (!into.contains(it.key())) {
            into[it.key()] = std::move(it.value());
        } else if (!MergeInto(into[it.key()], std::move(it.value()))) {
            return false;
        }
    }
    return true;
}

}  // namespace

void ConfigSection::Rename(const std::string& old_key, const std::string& new_key) {
    const std::string from = Join(path_, old_key), to = Join(path_, new_key);
    nlohmann::json* value = Find(state_->root, from);
    if (value == nullptr) return;
    nlohmann::json moved = std::move(*value);
    // Remove the old key, then the sections it leaves empty.
    std::string parent = from;
    while (true) {
        const std::size_t dot = parent.rfind('.');
        nlohmann::json* owner =
            dot == std::string::npos ? &state_->root : Find(state_->root, parent.substr(0, dot));
        owner->erase(dot == std::string::npos ? parent : parent.substr(dot + 1));
        if (dot == std::string::npos || !owner->empty()) break;
        parent = parent.substr(0, dot);
    }
    // Into the new key, its sections created; a section there already is merged.
    nlohmann::json* into = Create(state_->root, to);
    if (into == nullptr) {
        throw InvalidArgument(fmt::format("{}: '{}' needs '{}' to be an object", state_->source,
                                          from, to.substr(0, to.rfind('.'))));
    }
    if (into->is_null()) {
        *into = std::move(moved);
    } else if (!MergeInto(*into, std::move(moved))) {
        throw InvalidArgument(fmt::format("{}: '{}' is given twice, also by its former name '{}'",
                                          state_->source, to, from));
    }
    LogWarning("{}: '{}' is now called '{}'", state_->source, from, to);
}

ConfigSection ConfigSection::Section(const std::string& key) {
    const nlohmann::json* j = Lookup(key);
    if (j != nullptr && !j->is_object()) TypeError(key, "an object");
    return ConfigSection(state_, Join(path_, key));
}

void ConfigSection::CheckAllUsed() const {
    CheckUsed(state_->root, "", state_->used, state_->source);
}

namespace {

void WriteMarkdownRows(const nlohmann::ordered_json& j, const std::string& path,
                       const std::vector<std::pair<std::string, std::string>>& help,
                       std::string& out) {
    for (auto it = j.begin(); it != j.end(); ++it) {
        const std::string full = Join(path, it.key());
        if (it.value().is_object()) {
            WriteMarkdownRows(it.value(), full, help, out);
            continue;
        }
        std::string text;
        for (const auto& [p, h] : help) {
            if (p == full) text = h;
        }
        std::string escaped;
        for (char c : text) escaped += c == '|' ? std::string("\\|") : std::string(1, c);
        out += fmt::format("| `{}` | `{}` | {} |\n", full, it.value().dump(), escaped);
    }
}

}  // namespace

std::vector<std::string> ConfigSection::RecordedKeys() const {
    std::vector<std::string> keys;
    for (const auto& [key, text] : state_->help) keys.push_back(key);
    return keys;
}

std::string ConfigSection::DumpMarkdown() const {
    std::string out;
    std::string loose;  // top-level values
    for (auto it = state_->defaults.begin(); it != state_->defaults.end(); ++it) {
        if (it.value().is_object()) continue;
        nlohmann::ordered_json one = nlohmann::ordered_json::object();
        one[it.key()] = it.value();
        WriteMarkdownRows(one, "", state_->help, loose);
    }
    const std::string header = "| key | default | meaning |\n|---|---|---|\n";
    if (!loose.empty()) out += header + loose + "\n";
    for (auto it = state_->defaults.begin(); it != state_->defaults.end(); ++it) {
        if (!it.value().is_object()) continue;
        std::string rows;
        WriteMarkdownRows(it.value(), it.key(), state_->help, rows);
        out += "## " + it.key() + "\n\n" + header + rows + "\n";
    }
    return out;
}

std::string ConfigSection::DumpText() const {
    std::string out;
    WriteDump(state_->defaults, "", state_->help, 0, out);
    return out + "\n";
}

}  // namespace multicue::io
