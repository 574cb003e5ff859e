#pragma once
/// \file report.html pages written off the hot path: a stream of frames (a manifest, a bag) hands
/// each perceived frame to a writer thread and goes on with the next frame, so that the page (its
/// rendering is about as long as the pipeline on a 640x480 frame) never paces the stream.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <filesystem>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "multicue/core/point_cloud.hpp"
#include "multicue/system/perceive.hpp"
#include "multicue/system/perceive_report.hpp"

namespace multicue {

/// Writes report.html pages on one background thread, in the order they were submitted. A full
/// queue (max_pending pages not yet written) makes Submit wait, so memory stays bounded when the
/// pages are slower than the frames. Errors are kept and rethrown by Finish (the first one).
class ReportWriter {
  public:
    /// Throws InvalidArgument for max_pending < 1.
    explicit ReportWriter(ReportParams params, std::size_t max_pending = 2);
    ReportWriter(const ReportWriter&) = delete;
    ReportWriter& operator=(const ReportWriter&) = delete;
    /// Waits for the pages still queued (errors are dropped; call Finish to see them).
    ~ReportWriter();

    /// Queues the page of one frame for `dir`/report.html: the cloud given to Perceive, its
    /// result and PerceiveResultJson() of it. Throws the first write error of an earlier page.
    void Submit(std::filesystem::path dir, PointCloud cloud, PerceiveResult result,
                nlohmann::ordered_json result_json);

    /// Waits until every queued page is written; throws the first error of any of them.
    void Finish();

  private:
    struct Job {
        std::filesystem::path dir;
        PointCloud cloud;
        PerceiveResult result;
        nlohmann::ordered_json json;
    };
    void Run();
    void RethrowError();

    ReportParams params_;
    std::size_t max_pending_;
    std::mutex mutex_;
    std::condition_variable changed_;
    std::deque<Job> queue_;
    bool busy_ = false;  // a page is being written
    bool stopping_ = false;
    std::exception_ptr error_;
    std::thread worker_;
};

/// Removes `dir`/report.html if it exists: a folder whose new result files are written before its
/// page must not show an earlier run's page meanwhile (or for good, if the run is interrupted).
/// Throws IoError when it cannot be removed.
void RemoveStaleReport(const std::filesystem::path& dir);

}  // namespace multicue
