#include "multicue/core/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>

namespace multicue {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void OnInterruptSignal(int signal_number) {
    if (g_interrupted != 0) {
        // A second request: the user insists; restore the default action and re-raise.
        std::signal(signal_number, SIG_DFL);
        std::raise(signal_number);
        return;
    }
    g_interrupted = 1;
}

std::string FormatSeconds(double seconds) {
    char buffer[32];
    if (seconds < 60.0) {
        std::snprintf(buffer, sizeof(buffer), "%.1fs", seconds);
    } else {
        const int total = static_cast<int>(seconds + 0.5);
        std::snprintf(buffer, sizeof(buffer), "%dm%02ds", total / 60, total % 60);
    }
    return buffer;
}

}  // namespace

Progress::Progress(std::string label, std::size_t total, ProgressStyle style)
    : label_(std::move(label)), total_(total), style_(style) {
    if (style_ == ProgressStyle::kAuto) {
        style_ = isatty(fileno(stderr)) != 0 ? ProgressStyle::kBar : ProgressStyle::kLines;
    }
    start_ = std::chrono::steady_clock::now();
    last_draw_ = start_ - std::chrono::seconds(1);
}

Progress::~Progress() { Finish(); }

void Progress::Advance(std::size_t steps) {
    const std::size_t done = done_.fetch_add(steps) + steps;
    if (style_ == ProgressStyle::kSilent) return;
    Report(done, false);
}

void Progress::Finish() {
    if (style_ == ProgressStyle::kSilent) return;
    Report(done_.load(), true);
}

void Progress::Report(std::size_t done, bool final) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    if (final) finished_ = true;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double fraction =
        total_ == 0 ? 1.0 : std::min(1.0, static_cast<double>(done) / static_cast<double>(total_));
    if (style_ == ProgressStyle::kBar) {
        if (!final && now - last_draw_ < std::chrono::milliseconds(100)) return;
        last_draw_ = now;
        constexpr int kWidth = 30;
        const int filled = static_cast<int>(fraction * kWidth);
        std::string bar(static_cast<std::size_t>(filled), '#');
        bar.resize(kWidth, '.');
        std::string eta;
        if (!final && done > 0 && fraction < 1.0) {
            eta = " eta " + FormatSeconds(elapsed / fraction - elapsed);
        }
        std::fprintf(stderr, "\r%s [%s] %zu/%zu %3d%% %s%s\033[K%s", label_.c_str(), bar.c_str(),
                     done, total_, static_cast<int>(fraction * 100.0),
                     FormatSeconds(elapsed).c_str(), eta.c_str(), final ? "\n" : "");
    } else {
        const int decile = static_cast<int>(fraction * 10.0);
        // Every new tenth, and the final count unless that line was just printed.
        if (decile <= last_decile_ && !(final && done != last_printed_)) return;
        last_decile_ = decile;
        last_printed_ = done;
        std::fprintf(stderr, "%s: %zu/%zu (%d%%) %s\n", label_.c_str(), done, total_,
                     static_cast<int>(fraction * 100.0), FormatSeconds(elapsed).c_str());
    }
    std::fflush(stderr);
}

void InstallInterruptHandler() {
    std::signal(SIGINT, OnInterruptSignal);
    std::signal(SIGTERM, OnInterruptSignal);
}

bool InterruptRequested() { return g_interrupted != 0; }

void RequestInterrupt(bool requested) { g_interrupted = requested ? 1 : 0; }

}  // namespace multicue
