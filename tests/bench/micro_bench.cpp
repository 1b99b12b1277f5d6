// SPDX-License-Identifier: Apache-2.0
// Micro-benchmarks (Google Benchmark): Embree ray pairs per API, key and hash functions (one at a
// time and in SIMD batches), runtime lookups (single, batched, binary search) on a
// 2^22-capacity cache with 1 M live voxels next to a raw random-memory-access baseline of the
// same footprint, open + validate.
// `--smoke` shrinks every data set so the whole binary runs in about a second (ctest).
// SHARCBAKE_SCENES_DIR overrides the scenes folder compiled in.
// Figures and commands: BENCHMARKS.md.
#include "../cache_format/synthetic_cache.h"
#include "bench_support.h"

#include "sharcbake/runtime.h"
#include "sharcbake/scene_loader.h"

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <cstring>
#include <memory>
#include <numeric>
#include <random>
#include <stdexcept>

using namespace sharcbake;
using namespace sharcbake::bench;

namespace {

bool g_smoke = false;

/// The Cornell box and its ray pairs, built on first use.
struct RayFixture {
    std::unique_ptr<BakeScene> scene;
    std::vector<RayPair> pairs;
    static RayFixture& get() {
        static RayFixture fixture = [] {
            RayFixture f;
            // The scenes folder of the build, unless SHARCBAKE_SCENES_DIR names another (a
            // binary copied to a machine without the source tree).
            const char* scenes = std::getenv("SHARCBAKE_SCENES_DIR");
            f.scene = std::make_unique<BakeScene>(
                loadGltf(std::string(scenes ? scenes : SHARCBAKE_SCENES_DIR) + "/cornell_box/cornell_box.gltf"));
            f.pairs = makeRayPairs(f.scene->tracer, f.scene->lights, f.scene->camera_path, g_smoke ? 2048 : 1u << 17, 11);
            return f;
        }();
        return fixture;
    }
};

/// The runtime's cache and its queries, in random order (every query hits).
struct CacheFixture {
    std::vector<uint8_t> bytes;
    CacheView view;          ///< with the lookup index
    CacheView plain;         ///< without: binary search over the keys
    std::vector<Float3> positions, normals;
    size_t live = 0;
    static CacheFixture& get() {
        static CacheFixture fixture = [] {
            CacheFixture f;
            f.live = g_smoke ? 20000 : 1000000;
            std::vector<Float3> points, normals;
            std::mt19937 random(1234);
            const CacheData data = makeSyntheticCache(f.live, 1u << 22, random, points, normals);
            std::string message;
            if (encodeCacheFile(data, &f.bytes, &message) != CacheFileStatus::kOk) throw std::runtime_error(message);
            if (CacheView::openMemory(f.bytes.data(), f.bytes.size(), &f.view, nullptr) != CacheFileStatus::kOk ||
                CacheView::openMemory(f.bytes.data(), f.bytes.size(), &f.plain, nullptr) != CacheFileStatus::kOk ||
                f.view.buildLookupIndex() != CacheFileStatus::kOk) {
                throw std::runtime_error("synthetic cache does not open");
            }
            const size_t queries = g_smoke ? 1u << 14 : 1u << 22;
            std::mt19937 rng(99);
            std::uniform_int_distribution<size_t> pick(0, f.live - 1);
            for (size_t i = 0; i < queries; ++i) {
                const size_t j = pick(rng);
                f.positions.push_back(points[j]);
                f.normals.push_back(normals[j]);
            }
            return f;
        }();
        return fixture;
    }
};

constexpr Float3 kCamera{0.0f, 0.0f, 0.0f};

void BM_RayPairs(benchmark::State& state, RayApi api) {
    RayFixture& f = RayFixture::get();
    constexpr size_t kBlock = 256;
    size_t at = 0;
    for (auto _ : state) {
        if (at + kBlock > f.pairs.size()) at = 0;
        benchmark::DoNotOptimize(tracePairs(f.scene->tracer, f.pairs.data() + at, kBlock, api));
        at += kBlock;
    }
    state.SetItemsProcessed(int64_t(state.iterations() * kBlock));
    state.SetLabel("closest-hit + shadow pairs, Cornell box, 1 thread");
}
BENCHMARK_CAPTURE(BM_RayPairs, single, RayApi::Single);
BENCHMARK_CAPTURE(BM_RayPairs, stream, RayApi::Stream);
BENCHMARK_CAPTURE(BM_RayPairs, packet8, RayApi::Packet8);
BENCHMARK_CAPTURE(BM_RayPairs, packet16, RayApi::Packet16);

/// The tracer's closest hits in blocks of 256 of the pairs' first rays (Embree's packets of 16, each
/// hit's distance and barycentrics then recomputed), and the recomputation alone on those hits:
/// what hits whose bits do not depend on Embree's kernels cost.
void BM_TracerClosestHits(benchmark::State& state) {
    RayFixture& f = RayFixture::get();
    constexpr size_t kBlock = 256;
    std::vector<Ray> rays;
    for (const RayPair& pair : f.pairs) rays.push_back(pair.closest);
    std::vector<RayHit> hits(kBlock);
    std::vector<uint8_t> found(kBlock);
    size_t at = 0;
    for (auto _ : state) {
        if (at + kBlock > rays.size()) at = 0;
        f.scene->tracer.intersectMany(rays.data() + at, kBlock, hits.data(), found.data());
        benchmark::DoNotOptimize(hits.data());
        at += kBlock;
    }
    state.SetItemsProcessed(int64_t(state.iterations() * kBlock));
    state.SetLabel("closest hits, Cornell box, 1 thread");
}
BENCHMARK(BM_TracerClosestHits);

void BM_RecomputeHit(benchmark::State& state) {
    RayFixture& f = RayFixture::get();
    std::vector<Ray> rays;
    std::vector<RayHit> hits;
    for (const RayPair& pair : f.pairs) {
        RayHit hit;
        if (f.scene->tracer.intersect(pair.closest, hit)) {
            rays.push_back(pair.closest);
            hits.push_back(hit);
        }
    }
    size_t at = 0;
    for (auto _ : state) {
        if (at == hits.size()) at = 0;
        RayHit hit = hits[at];
        recomputeHit(f.scene->scene, rays[at], hit);
        benchmark::DoNotOptimize(hit);
        ++at;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
    state.SetLabel("one hit's distance and barycentrics, Cornell box");
}
BENCHMARK(BM_RecomputeHit);

void BM_HashGridKey(benchmark::State& state) {
    CacheFixture& f = CacheFixture::get();
    HashGridParameters params = f.view.gridParameters(kCamera);
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(hashGridKey(f.positions[i], f.normals[i], params));
        if (++i == f.positions.size()) i = 0;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_HashGridKey);

void BM_CacheViewKeyFor(benchmark::State& state) {
    CacheFixture& f = CacheFixture::get();
    size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(f.view.keyFor(f.positions[i], f.normals[i], kCamera));
        if (++i == f.positions.size()) i = 0;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_CacheViewKeyFor);

void BM_CacheViewKeysFor(benchmark::State& state) {
    CacheFixture& f = CacheFixture::get();
    constexpr size_t kBatch = 1024;
    std::vector<uint64_t> keys(kBatch);
    size_t at = 0;
    for (auto _ : state) {
        if (at + kBatch > f.positions.size()) at = 0;
        f.view.keysFor(kBatch, f.positions.data() + at, f.normals.data() + at, kCamera, keys.data());
        benchmark::DoNotOptimize(keys.data());
        at += kBatch;
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kBatch));
}
BENCHMARK(BM_CacheViewKeysFor);

void BM_HashGridHash(benchmark::State& state) {
    uint64_t key = 0x0123456789ABCDEFull;
    for (auto _ : state) {
        const uint32_t h = hashGridHash(key);
        benchmark::DoNotOptimize(h);
        key += 0x9E3779B97F4A7C15ull;
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
}
BENCHMARK(BM_HashGridHash);

void BM_QuerySingle(benchmark::State& state, bool indexed) {
    CacheFixture& f = CacheFixture::get();
    const CacheView& view = indexed ? f.view : f.plain;
    size_t i = 0, hits = 0;
    for (auto _ : state) {
        Float3 radiance;
        hits += view.lookup(f.positions[i], f.normals[i], kCamera, &radiance);
        benchmark::DoNotOptimize(radiance);
        if (++i == f.positions.size()) i = 0;
    }
    if (hits != size_t(state.iterations())) state.SkipWithError("a query missed");
    state.SetItemsProcessed(int64_t(state.iterations()));
    state.SetLabel(std::to_string(f.live) + " live voxels, capacity 2^22, random order");
}
BENCHMARK_CAPTURE(BM_QuerySingle, indexed, true);
BENCHMARK_CAPTURE(BM_QuerySingle, binary_search, false);

void BM_QueryBatched(benchmark::State& state) {
    CacheFixture& f = CacheFixture::get();
    const size_t batch = size_t(state.range(0));
    std::vector<Float3> radiance(batch);
    size_t at = 0;
    for (auto _ : state) {
        if (at + batch > f.positions.size()) at = 0;
        const size_t hits =
            f.view.lookupBatch(batch, f.positions.data() + at, f.normals.data() + at, kCamera, radiance.data());
        if (hits != batch) state.SkipWithError("a query missed");
        benchmark::DoNotOptimize(radiance.data());
        at += batch;
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(batch));
}
BENCHMARK(BM_QueryBatched)->Arg(64)->Arg(1024);

/// Raw random memory access over a table as large as the lookup index: the hardware's floor.
/// Dependent: each read's address comes from the previous read (latency). Independent: the
/// addresses are known ahead (throughput, as many misses in flight as the core allows).
struct RandomTable {
    std::vector<uint64_t> next;      ///< a single random cycle (Sattolo)
    std::vector<uint32_t> indices;   ///< random indices for the independent reads
    static RandomTable& get() {
        static RandomTable table = [] {
            RandomTable t;
            const size_t n = g_smoke ? 1u << 16 : 1u << 23;  // 64 MiB of u64 (the index's footprint)
            t.next.resize(n);
            std::iota(t.next.begin(), t.next.end(), 0);
            std::mt19937_64 rng(5);
            for (size_t i = n - 1; i > 0; --i) std::swap(t.next[i], t.next[std::uniform_int_distribution<size_t>(0, i - 1)(rng)]);
            t.indices.resize(g_smoke ? 1u << 14 : 1u << 22);
            for (uint32_t& i : t.indices) i = uint32_t(std::uniform_int_distribution<size_t>(0, n - 1)(rng));
            return t;
        }();
        return table;
    }
};

void BM_RandomRead_Dependent(benchmark::State& state) {
    RandomTable& t = RandomTable::get();
    uint64_t at = 0;
    for (auto _ : state) {
        at = t.next[at];
        benchmark::DoNotOptimize(at);
    }
    state.SetItemsProcessed(int64_t(state.iterations()));
    state.SetLabel(std::to_string(t.next.size() * 8 >> 20) + " MiB");
}
BENCHMARK(BM_RandomRead_Dependent);

void BM_RandomRead_Independent(benchmark::State& state) {
    RandomTable& t = RandomTable::get();
    constexpr size_t kBlock = 1024;
    size_t at = 0;
    uint64_t sum = 0;
    for (auto _ : state) {
        if (at + kBlock > t.indices.size()) at = 0;
        for (size_t i = 0; i < kBlock; ++i) sum += t.next[t.indices[at + i]];
        at += kBlock;
    }
    benchmark::DoNotOptimize(sum);
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(kBlock));
    state.SetLabel(std::to_string(t.next.size() * 8 >> 20) + " MiB");
}
BENCHMARK(BM_RandomRead_Independent);

void BM_OpenValidate(benchmark::State& state) {
    CacheFixture& f = CacheFixture::get();
    for (auto _ : state) {
        CacheView view;
        if (CacheView::openMemory(f.bytes.data(), f.bytes.size(), &view, nullptr) != CacheFileStatus::kOk) {
            state.SkipWithError("open failed");
        }
        benchmark::DoNotOptimize(view.voxelCount());
    }
    state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(f.bytes.size()));
}
BENCHMARK(BM_OpenValidate);

void BM_BuildLookupIndex(benchmark::State& state) {
    CacheFixture& f = CacheFixture::get();
    for (auto _ : state) {
        CacheView view;
        CacheView::openMemory(f.bytes.data(), f.bytes.size(), &view, nullptr);
        if (view.buildLookupIndex() != CacheFileStatus::kOk) state.SkipWithError("index failed");
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(f.live));
}
BENCHMARK(BM_BuildLookupIndex);

}  // namespace

int main(int argc, char** argv) {
    // --smoke (ours) shrinks the data sets; everything else goes to Google Benchmark.
    std::vector<char*> args;
    for (int i = 0; i < argc; ++i) {
        if (std::strcmp(argv[i], "--smoke") == 0) {
            g_smoke = true;
        } else {
            args.push_back(argv[i]);
        }
    }
    int count = int(args.size());
    benchmark::Initialize(&count, args.data());
    if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
