#include "multicue/io/config.hpp"

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"

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
        state->root = nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/true);
    } catch (const nlohmann::json::parse_error& e) {
        std::string what = e.what();
        const auto pos = what.find("parse error");
        throw InvalidArgument(fmt::format("{}: malformed JSON: {}", source,
                                          pos == std::string::npos ? what : what.substr(pos)));
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
    const nlohmann::json* node = &state_->root;
    std::size_t start = 0;
    while (true) {
        const std::size_t dot = full.find('.', start);
        const std::string part = full.substr(start, dot == std::string::npos ? dot : dot - start);
        if (!node->is_object() || !node->contains(part)) return nullptr;
        node = &(*node)[part];
        if (dot == std::string::npos) break;
        start = dot + 1;
    }
    state_->used.insert(full);
    return node;
}

void ConfigSection::Record(const std::string& key, nlohmann::json value, const std::string& help) {
    const std::string full = Join(path_, key);
    nlohmann::ordered_json* node = &state_->defaults;
    std::size_t start = 0;
    while (true) {
        const std::size_t dot = full.find('.', start);
        const std::string part = full.substr(start, dot == std::string::npos ? dot : dot - start);
        if (dot == std::string::npos) {
            (*node)[part] = nlohmann::ordered_json(value);
            break;
        }
        node = &(*node)[part];
        start = dot + 1;
    }
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
        if (!j->is_array() || j->size() != 3 || !(*j)[0].is_number() || !(*j)[1].is_number() ||
            !(*j)[2].is_number()) {
            TypeError(key, "an array of three numbers");
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

ConfigSection ConfigSection::Section(const std::string& key) {
    const nlohmann::json* j = Lookup(key);
    if (j != nullptr && !j->is_object()) TypeError(key, "an object");
    return ConfigSection(state_, Join(path_, key));
}

void ConfigSection::CheckAllUsed() const {
    CheckUsed(state_->root, "", state_->used, state_->source);
}

std::string ConfigSection::DumpText() const {
    std::string out;
    WriteDump(state_->defaults, "", state_->help, 0, out);
    return out + "\n";
}

}  // namespace multicue::io
