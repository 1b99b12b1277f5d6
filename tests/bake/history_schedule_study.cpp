// SPDX-License-Identifier: Apache-2.0
// The measurement behind the default --history: furnace (rho 0.9, every surface's radiance
// exactly 10) baked with each schedule; the mean relative error of the voxels with at least 32
// samples, and the share within 2%, at power-of-two iteration counts. A study, not a test.
// Usage: history_schedule_study [SCENES_DIR]   (prints one line per schedule)
#include "sharc/baker.h"
#include "sharcbake/scene_loader.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    using namespace sharcbake;
    const std::string scenes = argc > 1 ? argv[1] : SHARCBAKE_SCENES_DIR;
    const Scene scene = loadGltf(scenes + "/furnace_rho090/furnace_rho090.gltf");
    const Tracer tracer(scene);
    const LightSampler lights(scene);
    const CameraPath path = exploringCameraPath(tracer, scene, 16, 3).value();  // the furnace's one camera
    constexpr double kExpected = 10.0;  // Le / (1 - rho)

    for (const char* history : {"window:20", "window:64", "average", "ramp:2", "ramp:4", "ramp:8"}) {
        for (uint32_t depth : {2u, 8u}) {
            BakeSettings settings;
            settings.width = settings.height = 160;
            settings.sharc.grid.capacity = 1u << 18;
            settings.sharc.grid.scene_scale = 5.0f;
            HistorySchedule::parse(history, settings.sharc.history);
            settings.sharc.propagation_depth = depth;
            settings.path.max_bounces = std::max(8u, depth + 2);
            Baker baker(tracer, lights, path, settings, SharcCache::chooseRadianceScale(estimateMaxRadiance(tracer)));
            const auto start = std::chrono::steady_clock::now();
            std::printf("%-9s depth %u:", history, depth);
            for (uint32_t i = 1; i <= 512; ++i) {
                baker.runIteration();
                if (i < 16 || (i & (i - 1)) != 0) continue;
                const SharcCache& cache = baker.cache();
                double sum = 0.0, worst = 0.0;
                uint32_t n = 0, within = 0;
                for (uint32_t s = 0; s < cache.capacity(); ++s) {
                    const ResolvedEntry& r = cache.resolved()[s];
                    if (!(r.weight > 0.0) || r.total_samples < 32) continue;
                    const double e = std::abs(double(r.mean.x) - kExpected) / kExpected;
                    sum += e;
                    worst = std::max(worst, e);
                    within += e <= 0.02;
                    ++n;
                }
                const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
                std::printf("  [%u it %.1fs mean %.4f max %.3f within2%% %.3f]", i, seconds, sum / std::max(n, 1u),
                            worst, double(within) / std::max(n, 1u));
            }
            std::printf("\n");
            std::fflush(stdout);
        }
    }
    return 0;
}
