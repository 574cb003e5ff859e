#include "multicue/ml/svm_model_text.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <vector>

#include <fmt/format.h>

namespace multicue::ml {
namespace {

std::vector<std::string_view> SplitFields(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

std::optional<long long> Integer(std::string_view s) {
    long long v = 0;
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size()) return std::nullopt;
    return v;
}

// As libsvm reads it (strtod), but the whole token and finite.
std::optional<double> Real(std::string_view s) {
    const std::string text(s);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

class Checker {
  public:
    Checker(std::string_view text, std::size_t num_features, std::size_t max_classes)
        : num_features_(num_features), max_classes_(max_classes) {
        std::size_t pos = 0;
        while (pos < text.size()) {
            const std::size_t eol = text.find('\n', pos);
            const std::size_t end = eol == std::string_view::npos ? text.size() : eol;
            lines_.push_back(text.substr(pos, end - pos));
            pos = end + 1;
        }
    }

    std::string Run() {
        std::string problem = Header();
        if (problem.empty()) problem = SupportVectors();
        return problem;
    }

  private:
    // The header keys in svm_save_model's order; `optional` ones may be missing.
    std::string Header() {
        if (auto p = Key("svm_type", 1); !p.empty()) return p;
        if (tokens_[1] != "c_svc") return "svm_type must be c_svc";
        if (auto p = Key("kernel_type", 1); !p.empty()) return p;
        const bool rbf = tokens_[1] == "rbf";
        if (!rbf && tokens_[1] != "linear") return "kernel_type must be linear or rbf";
        if (rbf) {
            if (auto p = Key("gamma", 1); !p.empty()) return p;
            if (!Real(tokens_[1])) return "gamma is not a finite number";
        }
        if (auto p = Key("nr_class", 1); !p.empty()) return p;
        const auto n = Integer(tokens_[1]);
        if (!n || *n < 2 || static_cast<unsigned long long>(*n) > max_classes_) {
            return fmt::format("nr_class must be in [2, {}]", max_classes_);
        }
        classes_ = static_cast<std::size_t>(*n);
        const std::size_t pairs = classes_ * (classes_ - 1) / 2;
        if (auto p = Key("total_sv", 1); !p.empty()) return p;
        const auto l = Integer(tokens_[1]);
        // One line per support vector follows the header.
        if (!l || *l < 1 || static_cast<unsigned long long>(*l) > lines_.size()) {
            return "total_sv does not match the lines of the file";
        }
        total_sv_ = static_cast<std::size_t>(*l);
        if (auto p = Reals("rho", pairs); !p.empty()) return p;
        if (auto p = Key("label", classes_); !p.empty()) return p;
        for (std::size_t k = 1; k < tokens_.size(); ++k) {
            const auto label = Integer(tokens_[k]);
            if (!label || *label < 0 || static_cast<unsigned long long>(*label) >= max_classes_) {
                return "a label is not a class index";
            }
        }
        if (Peek() == "probA") {
            if (auto p = Reals("probA", pairs); !p.empty()) return p;
            if (auto p = Reals("probB", pairs); !p.empty()) return p;
        }
        if (auto p = Key("nr_sv", classes_); !p.empty()) return p;
        long long sum = 0;
        for (std::size_t k = 1; k < tokens_.size(); ++k) {
            const auto count = Integer(tokens_[k]);
            if (!count || *count < 0) return "nr_sv holds a count that is not a number >= 0";
            sum += *count;
            if (sum > static_cast<long long>(total_sv_)) break;
        }
        if (sum != static_cast<long long>(total_sv_)) return "nr_sv does not add up to total_sv";
        if (auto p = Key("SV", 0); !p.empty()) return p;
        return "";
    }

    // One support vector per line: nr_class - 1 coefficients, then index:value pairs with
    // ascending indices in [1, num_features].
    std::string SupportVectors() {
        for (std::size_t i = 0; i < total_sv_; ++i, ++line_) {
            if (line_ >= lines_.size()) return "fewer support vectors than total_sv";
            const auto tokens = SplitFields(lines_[line_]);
            if (tokens.size() < classes_ - 1) return "a support vector lacks its coefficients";
            for (std::size_t k = 0; k < classes_ - 1; ++k) {
                if (!Real(tokens[k])) return "a support vector coefficient is not a finite number";
            }
            long long last = 0;
            for (std::size_t k = classes_ - 1; k < tokens.size(); ++k) {
                const std::size_t colon = tokens[k].find(':');
                if (colon == std::string_view::npos)
                    return "a support vector entry is not index:value";
                const auto index = Integer(tokens[k].substr(0, colon));
                if (!index || *index <= last ||
                    static_cast<unsigned long long>(*index) > num_features_) {
                    return "a support vector index is out of order or beyond the features";
                }
                if (!Real(tokens[k].substr(colon + 1))) {
                    return "a support vector value is not a finite number";
                }
                last = *index;
            }
        }
        for (; line_ < lines_.size(); ++line_) {
            if (!SplitFields(lines_[line_]).empty()) return "more support vectors than total_sv";
        }
        return "";
    }

    std::string_view Peek() const {
        if (line_ >= lines_.size()) return {};
        const auto t = SplitFields(lines_[line_]);
        return t.empty() ? std::string_view() : t.front();
    }

    // The next line must be `key` with `values` values; they are left in tokens_[1...].
    std::string Key(std::string_view key, std::size_t values) {
        if (line_ >= lines_.size()) return fmt::format("'{}' is missing", key);
        for (const char c : lines_[line_]) {
            if (c == '\r' || c == '\0') return "control characters in the model text";
        }
        tokens_ = SplitFields(lines_[line_++]);
        if (tokens_.empty() || tokens_[0] != key) return fmt::format("'{}' expected", key);
        if (tokens_.size() != values + 1) {
            return fmt::format("'{}' needs {} values, got {}", key, values, tokens_.size() - 1);
        }
        return "";
    }

    std::string Reals(std::string_view key, std::size_t values) {
        if (auto p = Key(key, values); !p.empty()) return p;
        for (std::size_t k = 1; k < tokens_.size(); ++k) {
            if (!Real(tokens_[k])) return fmt::format("'{}' holds a value that is not finite", key);
        }
        return "";
    }

    std::vector<std::string_view> lines_;
    std::vector<std::string_view> tokens_;
    std::size_t line_ = 0;
    std::size_t num_features_;
    std::size_t max_classes_;
    std::size_t classes_ = 0;
    std::size_t total_sv_ = 0;
};

}  // namespace

std::string SvmModelTextProblem(std::string_view text, std::size_t num_features,
                                std::size_t max_classes) {
    return Checker(text, num_features, max_classes).Run();
}

}  // namespace multicue::ml
