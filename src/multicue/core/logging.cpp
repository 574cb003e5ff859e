#include "multicue/core/logging.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>

#include "multicue/core/exceptions.hpp"

namespace multicue {
namespace {

std::atomic<LogLevel> g_level{LogLevel::kWarning};
std::mutex g_sink_mutex;
LogSink g_sink;

const char* LevelName(LogLevel level) {
    switch (level) {
        case LogLevel::kDebug:
            return "debug";
        case LogLevel::kInfo:
            return "info";
        case LogLevel::kWarning:
            return "warning";
        case LogLevel::kError:
            return "error";
        case LogLevel::kOff:
            break;
    }
    return "off";
}

}  // namespace

void SetLogLevel(LogLevel level) { g_level.store(level); }
LogLevel GetLogLevel() { return g_level.load(); }

void SetLogSink(LogSink sink) {
    std::lock_guard lock(g_sink_mutex);
    g_sink = std::move(sink);
}

LogLevel ParseLogLevel(std::string_view name) {
    for (auto level : {LogLevel::kDebug, LogLevel::kInfo, LogLevel::kWarning, LogLevel::kError,
                       LogLevel::kOff}) {
        if (name == LevelName(level)) return level;
    }
    throw InvalidArgument(
        fmt::format("log level must be one of debug, info, warning, error, off; got '{}'", name));
}

namespace detail {
void LogMessage(LogLevel level, std::string_view message) {
    std::lock_guard lock(g_sink_mutex);
    if (g_sink) {
        g_sink(level, message);
        return;
    }
    std::fprintf(stderr, "[multicue] %s: %.*s\n", LevelName(level),
                 static_cast<int>(message.size()), message.data());
}
}  // namespace detail

}  // namespace multicue
