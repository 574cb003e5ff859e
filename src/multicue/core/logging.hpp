#pragma once
/// \file One logger with levels for the whole library. Library code never prints directly;
/// applications choose the level and, if they want, their own sink. Never log inside parallel
/// loops.

#include <functional>
#include <string>
#include <string_view>
#include <utility>

#include <fmt/format.h>

namespace multicue {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3, kOff = 4 };

/// Receives every message at or above the current level.
using LogSink = std::function<void(LogLevel, std::string_view)>;

void SetLogLevel(LogLevel level);
LogLevel GetLogLevel();
/// Replaces the sink (default: "[multicue] level: message" on stderr). An empty sink restores it.
void SetLogSink(LogSink sink);
/// Parses "debug", "info", "warning", "error" or "off"; throws InvalidArgument otherwise.
LogLevel ParseLogLevel(std::string_view name);

namespace detail {
void LogMessage(LogLevel level, std::string_view message);
}

template <typename... Args>
void Log(LogLevel level, fmt::format_string<Args...> format, Args&&... args) {
    if (level < GetLogLevel()) return;
    detail::LogMessage(level, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void LogDebug(fmt::format_string<Args...> format, Args&&... args) {
    Log(LogLevel::kDebug, format, std::forward<Args>(args)...);
}
template <typename... Args>
void LogInfo(fmt::format_string<Args...> format, Args&&... args) {
    Log(LogLevel::kInfo, format, std::forward<Args>(args)...);
}
template <typename... Args>
void LogWarning(fmt::format_string<Args...> format, Args&&... args) {
    Log(LogLevel::kWarning, format, std::forward<Args>(args)...);
}
template <typename... Args>
void LogError(fmt::format_string<Args...> format, Args&&... args) {
    Log(LogLevel::kError, format, std::forward<Args>(args)...);
}

}  // namespace multicue
