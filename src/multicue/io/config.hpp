#pragma once
/// \file Parameter files: one JSON object whose nested objects mirror the Params structs. Every key
/// of the file must be consumed; an unknown key is an error naming its full path, so a typo never
/// silently leaves a default in place.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "multicue/core/params.hpp"
#include "multicue/io/json_text.hpp"

namespace multicue::io {

/// A view of one JSON object of a parameter file. Read values with Get(); absent keys leave the
/// default untouched; keys of the wrong type throw InvalidArgument naming `section.key`.
/// In dump mode (no file), Get() records the defaults instead, so the same code that reads a
/// configuration also prints the default one.
class ConfigSection {
  public:
    /// Reads a JSON object from `text`; `source` names it in error messages.
    static ConfigSection Parse(const std::string& text, const std::string& source);
    /// Reads a JSON parameter file. Throws IoError or InvalidArgument (malformed JSON).
    static ConfigSection Load(const std::filesystem::path& path);
    /// An empty section that records defaults (for `--dump`).
    static ConfigSection Dump();

    template <typename T>
    void Get(const std::string& key, T& value, const std::string& help = "");
    void Get(const std::string& key, Eigen::Vector3f& value, const std::string& help = "");
    /// An optional vector: `null` or absent leaves it empty.
    void Get(const std::string& key, std::optional<Eigen::Vector3f>& value,
             const std::string& help = "");

    /// A string that must be one of `choices`; InvalidArgument naming `section.key` and the
    /// choices otherwise. The dump lists the choices after the help text.
    void GetChoice(const std::string& key, std::string& value,
                   std::span<const std::string_view> choices, const std::string& help = "");

    /// Nested section `key` (empty if absent).
    ConfigSection Section(const std::string& key);

    /// The visitor interface of parameter structs: a struct P lists its parameters once, in
    /// `template <typename V> void VisitParams(V& v)`, with `v(key, field, help)` per value,
    /// `v.Node(key, sub)` per nested struct, `v.Switch(key, step, help)` per optional step and
    /// `v.GetChoice(key, name, choices, help)` per named option;
    /// a section then reads them (or records them in dump mode).
    template <typename T>
    void operator()(const std::string& key, T& value, const std::string& help) {
        Get(key, value, help);
    }
    /// A nested struct's parameters in section `key`.
    template <typename P>
    void Node(const std::string& key, P& params) {
        ConfigSection sub = Section(key);
        params.VisitParams(sub);
    }
    /// An optional step in section `key`: its "enabled" switch (meaning `help`), then its own
    /// parameters.
    template <typename P>
    void Switch(const std::string& key, Switchable<P>& step, const std::string& help) {
        ConfigSection sub = Section(key);
        sub.Get("enabled", step.enabled, help);
        static_cast<P&>(step).VisitParams(sub);
    }

    /// A key of an earlier release: when the file has `old_key` (a dotted path below this
    /// section; a value or a whole section), it is read as `new_key` and a warning names both.
    /// Sections are merged into an existing new section; a value given under both names is an
    /// InvalidArgument. Sections left empty by the move are removed. Nothing in dump mode.
    void Rename(const std::string& old_key, const std::string& new_key);

    /// Throws InvalidArgument naming the first key that no Get()/Section() asked for.
    void CheckAllUsed() const;

    /// The recorded defaults (dump mode) as pretty JSON with help texts as "//" comments.
    std::string DumpText() const;
    /// The full key paths recorded so far (dump mode), in the order they were recorded.
    std::vector<std::string> RecordedKeys() const;
    /// The recorded defaults (dump mode) as a Markdown table: key path, default, meaning; one
    /// table per top-level section, each under a `## section` heading.
    std::string DumpMarkdown() const;

  private:
    struct State;
    ConfigSection(std::shared_ptr<State> state, std::string path);
    const nlohmann::json* Lookup(const std::string& key);
    void Record(const std::string& key, nlohmann::json value, const std::string& help);
    /// The float as the double with the same shortest decimal form (0.02f dumps as 0.02).
    static nlohmann::json FloatToJson(float value);
    [[noreturn]] void TypeError(const std::string& key, const char* expected) const;

    std::shared_ptr<State> state_;
    std::string path_;  // "" for the root, "a.b" for nested sections
};

template <typename T>
void ConfigSection::Get(const std::string& key, T& value, const std::string& help) {
    if (const nlohmann::json* j = Lookup(key)) {
        if constexpr (std::is_same_v<T, bool>) {
            if (!j->is_boolean()) TypeError(key, "true or false");
        } else if constexpr (std::is_integral_v<T>) {
            if (!j->is_number_integer()) TypeError(key, "an integer");
            if constexpr (std::is_unsigned_v<T>) {
                if (!j->is_number_unsigned() && j->get<std::int64_t>() < 0) {
                    TypeError(key, "a non-negative integer");
                }
            }
            // A value beyond the type would be cut to another, wrong value.
            if (!JsonIntegerFits<T>(*j)) TypeError(key, "an integer of a smaller magnitude");
        } else if constexpr (std::is_floating_point_v<T>) {
            if (!j->is_number()) TypeError(key, "a number");
            if (!(std::abs(j->get<double>()) <= std::numeric_limits<T>::max())) {
                TypeError(key, "a finite number of a smaller magnitude");
            }
        } else if constexpr (std::is_same_v<T, std::string>) {
            if (!j->is_string()) TypeError(key, "a string");
        }
        value = j->get<T>();
    } else if constexpr (std::is_same_v<T, float>) {
        Record(key, FloatToJson(value), help);
    } else {
        Record(key, value, help);
    }
}

}  // namespace multicue::io
