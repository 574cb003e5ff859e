#include "multicue/system/report_writer.hpp"

#include <fmt/format.h>

#include "multicue/core/exceptions.hpp"
#include "multicue/io/file_utils.hpp"

namespace multicue {

ReportWriter::ReportWriter(ReportParams params, std::size_t max_pending)
    : params_(params), max_pending_(max_pending) {
    if (max_pending < 1) {
        throw InvalidArgument(
            fmt::format("report writer: max_pending must be >= 1, got {}", max_pending));
    }
    worker_ = std::thread([this] { Run(); });
}

ReportWriter::~ReportWriter() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    changed_.notify_all();
    if (worker_.joinable()) worker_.join();
}

void ReportWriter::RethrowError() {
    if (error_) {
        std::exception_ptr e = error_;
        error_ = nullptr;
        std::rethrow_exception(e);
    }
}

void ReportWriter::Submit(std::filesystem::path dir, PointCloud cloud, PerceiveResult result,
                          nlohmann::ordered_json result_json) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.size() < max_pending_ || error_; });
    RethrowError();
    queue_.push_back({std::move(dir), std::move(cloud), std::move(result), std::move(result_json)});
    lock.unlock();
    changed_.notify_all();
}

void ReportWriter::Finish() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
    RethrowError();
}

void ReportWriter::Run() {
    for (;;) {
        Job job;
        {
            std::unique_lock lock(mutex_);
            changed_.wait(lock, [&] { return !queue_.empty() || stopping_; });
            if (queue_.empty()) return;
            job = std::move(queue_.front());
            queue_.pop_front();
            busy_ = true;
        }
        changed_.notify_all();
        std::exception_ptr failed;
        try {
            const std::string html =
                PerceiveReportPage(job.cloud, job.result, job.json, params_).Render();
            io::WriteFileAtomically(job.dir / "report.html",
                                    [&](std::ostream& out) { out << html; });
        } catch (...) {
            failed = std::current_exception();
        }
        {
            std::lock_guard lock(mutex_);
            busy_ = false;
            if (failed && !error_) error_ = failed;
        }
        changed_.notify_all();
    }
}

void RemoveStaleReport(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::remove(dir / "report.html", ec);
    if (ec) {
        throw IoError(fmt::format("{}: cannot remove the earlier report: {}",
                                  (dir / "report.html").string(), ec.message()));
    }
}

}  // namespace multicue
