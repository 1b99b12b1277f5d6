// SPDX-License-Identifier: Apache-2.0
#include "support/progress.h"

#include <unistd.h>

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

bool Progress::isTerminal() { return isatty(STDERR_FILENO) == 1; }

Progress::Progress(std::string label, uint64_t total_units, bool enabled)
    : label_(std::move(label)), total_(total_units), enabled_(enabled),
      start_(std::chrono::steady_clock::now()) {
    if (!enabled_) return;
    thread_ = std::thread([this] {
        std::unique_lock<std::mutex> lock(mutex_);
        while (!finished_) {
            draw(false);
            wake_.wait_for(lock, std::chrono::milliseconds(250));
        }
    });
}

Progress::~Progress() { finish(); }

void Progress::finish() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        if (finished_) return;
        finished_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
    if (enabled_) draw(true);
}

void Progress::draw(bool final_line) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
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

}  // namespace sharcbake
