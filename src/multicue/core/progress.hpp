#pragma once
/// \file Progress of long jobs (training, simulation, dataset extraction, evaluation) and a
/// cooperative interruption flag. On a terminal, Progress redraws one bar line on stderr; otherwise
/// it prints a plain line every 10 %. Library code reports progress only through a Progress passed
/// in by the caller, so tests and embedding applications stay silent by default.

#include <atomic>
#include <chrono>
#include <cstddef>
#include <functional>
#include <mutex>
#include <string>

namespace multicue {

/// How Progress reports.
enum class ProgressStyle {
    kAuto,   ///< a bar when stderr is a terminal, plain lines otherwise
    kBar,    ///< always a redrawn bar (carriage returns)
    kLines,  ///< always plain lines, one per 10 %
    kSilent  ///< nothing
};

/// Counts finished steps of a job of known size. Advance() may be called from several threads.
class Progress {
  public:
    /// A silent progress: counts, never prints.
    Progress() : Progress("", 0, ProgressStyle::kSilent) {}
    Progress(std::string label, std::size_t total, ProgressStyle style = ProgressStyle::kAuto);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// Marks `steps` more steps done.
    void Advance(std::size_t steps = 1);
    /// Prints the final state (once); called by the destructor if not before.
    void Finish();

    std::size_t done() const { return done_.load(); }
    std::size_t total() const { return total_; }

  private:
    void Report(std::size_t done, bool final);

    std::string label_;
    std::size_t total_ = 0;
    ProgressStyle style_ = ProgressStyle::kSilent;
    std::atomic<std::size_t> done_{0};
    std::mutex mutex_;
    int last_decile_ = -1;
    std::size_t last_printed_ = static_cast<std::size_t>(-1);
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_;
    bool finished_ = false;
};

/// Installs SIGINT/SIGTERM handlers that only set the interruption flag (the second signal
/// terminates at once). Long jobs poll InterruptRequested() between steps, finish the step at
/// hand, leave every written file complete, and stop.
void InstallInterruptHandler();
/// True once an interruption was requested (by a signal or RequestInterrupt()).
bool InterruptRequested();
/// Sets (true) or clears (false) the flag; used by tests and by embedding applications.
void RequestInterrupt(bool requested = true);

}  // namespace multicue
