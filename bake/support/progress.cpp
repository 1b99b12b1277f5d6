// SPDX-License-Identifier: Apache-2.0
#include "support/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sharcbake {

std::string formatDuration(double seconds) {
    char buffer[32];
    if (!std::isfinite(seconds) || seconds < 0.0) return "--";
    if (seconds < 60.0) {
        std::snprintf(buffer, sizeof buffer, "%.1fs", seconds);
    } else if (seconds < 3600.0) {
        const int s = int(seconds);
        std::snprintf(buffer, sizeof buffer, "%dm%02ds", s / 60, s % 60);
    } else {
        const int s = int(seconds);
        std::snprintf(buffer, sizeof buffer, "%dh%02dm", s / 3600, (s / 60) % 60);
    }
    return buffer;
}

bool Progress::stderrIsTerminal() { return isatty(STDERR_FILENO) == 1; }
bool Progress::stdoutIsTerminal() { return isatty(STDOUT_FILENO) == 1; }

ProgressOutput ProgressOutput::forCommand(bool quiet, double log_interval) {
    ProgressOutput output;
    if (quiet) return output;
    output.bar = Progress::stderrIsTerminal();
    output.log_interval = Progress::stdoutIsTerminal() ? 0.0 : log_interval;
    return output;
}

Progress::Progress(std::string label, std::string unit, uint64_t total_units, ProgressOutput output)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total_units), output_(output),
      start_(std::chrono::steady_clock::now()) {
    if (!output_.bar && output_.log_interval <= 0.0) return;
    thread_ = std::thread([this] {
        // The bar redraws four times a second; log lines come at whole multiples of the interval.
        constexpr double kBarPeriod = 0.25;
        std::unique_lock<std::mutex> lock(mutex_);
        double next_log = output_.log_interval;
        while (!finished_) {
            if (output_.bar) drawBar(false);
            if (output_.log_interval > 0.0 && elapsedSeconds() >= next_log) {
                printLogLine(false);
                while (next_log <= elapsedSeconds()) next_log += output_.log_interval;
            }
            double wait = output_.bar ? kBarPeriod : next_log - elapsedSeconds();
            if (output_.bar && output_.log_interval > 0.0) wait = std::min(wait, next_log - elapsedSeconds());
            wake_.wait_for(lock, std::chrono::duration<double>(std::max(wait, 0.001)));
        }
    });
}

Progress::~Progress() { finish(); }

void Progress::setDetail(std::string detail) {
    std::lock_guard<std::mutex> lock(mutex_);
    detail_ = std::move(detail);
}

void Progress::finish() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (finished_) return;
        finished_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (output_.bar) drawBar(true);
    // A job short enough to print no periodic line needs no closing one either.
    std::lock_guard<std::mutex> lock(mutex_);
    if (log_lines_ > 0) printLogLine(true);
}

double Progress::elapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::drawBar(bool final_line) {
    const double elapsed = elapsedSeconds();
    const uint64_t total = total_.load(std::memory_order_relaxed);
    const uint64_t done = std::min(done_.load(std::memory_order_relaxed), total);
    const double fraction = total > 0 ? double(done) / double(total) : 1.0;
    constexpr int kBarWidth = 30;
    const int filled = int(fraction * kBarWidth);
    std::string bar(size_t(filled), '#');
    bar.append(size_t(kBarWidth - filled), '.');
    const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : NAN;
    std::fprintf(stderr, "\r%s [%s] %3d%%  %s elapsed, ETA %s   ", label_.c_str(), bar.c_str(),
                 int(fraction * 100.0), formatDuration(elapsed).c_str(),
                 final_line ? "0.0s" : formatDuration(eta).c_str());
    if (final_line) std::fputc('\n', stderr);
    std::fflush(stderr);
}

/// "progress: Baking 120/512 iterations (23%), 14.2s elapsed, ETA 47.3s, 175828 voxels", or at
/// the end "progress: Baking 512/512 iterations (100%) in 60.1s, 175828 voxels". Flushed: a pipe
/// would otherwise hold the lines until the job ends.
void Progress::printLogLine(bool final_line) {
    const double elapsed = elapsedSeconds();
    const uint64_t total = total_.load(std::memory_order_relaxed);
    const uint64_t done = std::min(done_.load(std::memory_order_relaxed), total);
    const double fraction = total > 0 ? double(done) / double(total) : 1.0;
    std::string timing;
    if (final_line) {
        timing = " in " + formatDuration(elapsed);
    } else {
        const double eta = fraction > 0.0 ? elapsed * (1.0 - fraction) / fraction : NAN;
        timing = ", " + formatDuration(elapsed) + " elapsed, ETA " + formatDuration(eta);
    }
    std::printf("progress: %s %llu/%llu %s (%d%%)%s%s%s\n", label_.c_str(), (unsigned long long)done,
                (unsigned long long)total, unit_.c_str(), int(fraction * 100.0), timing.c_str(),
                detail_.empty() ? "" : ", ", detail_.c_str());
    std::fflush(stdout);
    ++log_lines_;
}

}  // namespace sharcbake
