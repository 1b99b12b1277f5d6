// SPDX-License-Identifier: Apache-2.0
/// @file progress.h
/// @brief Progress with ETA for long work. The work reports units done; a background thread
/// redraws one status line on stderr. Silent when disabled (not a TTY, or --quiet), so logs
/// and pipelines stay clean.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace sharcbake {

class Progress {
public:
    /// @param enabled draw the line at all (callers pass isTerminal() && !quiet)
    Progress(std::string label, uint64_t total_units, bool enabled);
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    void advance(uint64_t units = 1) { done_.fetch_add(units, std::memory_order_relaxed); }
    /// Changes the total, e.g. when a time budget turns out to stop the work early.
    void setTotal(uint64_t total) { total_.store(total, std::memory_order_relaxed); }
    /// Draws the final line and stops the thread; called by the destructor if not before.
    void finish();

    /// True if stderr is a terminal.
    static bool isTerminal();

private:
    void draw(bool final_line);

    std::string label_;
    std::atomic<uint64_t> total_;
    std::atomic<uint64_t> done_{0};
    bool enabled_;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::thread thread_;
};

/// "1h02m", "3m05s", "12.3s".
std::string formatDuration(double seconds);

}  // namespace sharcbake
