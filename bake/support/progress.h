// SPDX-License-Identifier: Apache-2.0
/// @file progress.h
/// @brief Progress with ETA for long work. The work reports units done; a background thread
/// redraws a status line on a terminal and, where the output goes to a log (a pipe, a file, a
/// CI job), prints a plain line at a fixed interval so that a long job never looks hung.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace sharcbake {

/// Where progress goes.
struct ProgressOutput {
    bool bar = false;           ///< a line on stderr, redrawn in place (needs a terminal)
    double log_interval = 0.0;  ///< seconds between plain lines on stdout; 0: none

    /// The tools' choice: the bar when stderr is a terminal, lines every `log_interval` seconds
    /// when stdout is not one, nothing with --quiet.
    static ProgressOutput forCommand(bool quiet, double log_interval);
};

class Progress {
public:
    /// @param unit what `total_units` counts, plural ("iterations", "pixels")
    Progress(std::string label, std::string unit, uint64_t total_units, ProgressOutput output);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void advance(uint64_t units = 1) { done_.fetch_add(units, std::memory_order_relaxed); }
    /// Changes the total, e.g. when a time budget turns out to stop the work early.
    void setTotal(uint64_t total) { total_.store(total, std::memory_order_relaxed); }
    /// Text appended to each log line ("175828 voxels"); any thread may set it.
    void setDetail(std::string detail);
    /// Draws the final line and stops the thread; called by the destructor if not before.
    void finish();

    /// True if stderr / stdout is a terminal.
    static bool stderrIsTerminal();
    static bool stdoutIsTerminal();

private:
    void drawBar(bool final_line);
    void printLogLine(bool final_line);
    double elapsedSeconds() const;

    std::string label_;
    std::string unit_;
    std::atomic<uint64_t> total_;
    std::atomic<uint64_t> done_{0};
    ProgressOutput output_;
    bool finished_ = false;
    std::string detail_;       ///< guarded by mutex_
    uint32_t log_lines_ = 0;  ///< periodic lines printed so far
    std::chrono::steady_clock::time_point start_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::thread thread_;
};

/// "1h02m", "3m05s", "12.3s".
std::string formatDuration(double seconds);

}  // namespace sharcbake
