// SPDX-License-Identifier: Apache-2.0
// Walls thinner than a voxel: surfaces either side share voxels once the roaming camera sees both.
#include "sharc/wall_leaks.h"
#include "test_rooms.h"

#include <gtest/gtest.h>

#include <limits>

namespace sharcbake {
namespace {

/// Two 5 x 3 x 5 rooms side by side along x, the partition (`gap` thick) at x = `wall`.
Scene twoRooms(float wall, float gap) {
    Scene scene = emptyTestScene();
    Material grey;
    grey.base_color = glm::vec3(0.8f);
    scene.materials.push_back(grey);
    addInwardBox(scene, glm::vec3(wall - 5.0f, 0.0f, -2.5f), glm::vec3(wall, 3.0f, 2.5f), 0u);
    addInwardBox(scene, glm::vec3(wall + gap, 0.0f, -2.5f), glm::vec3(wall + gap + 5.0f, 3.0f, 2.5f), 0u);
    return scene;
}

/// A camera in each room 4 units from the partition, and the waypoints the roaming camera visits.
struct Views {
    std::vector<glm::vec3> cameras;
    std::vector<glm::vec3> waypoints;
};
Views bothRooms(float wall) {
    Views v;
    v.cameras = {glm::vec3(wall - 4.0f, 1.5f, 2.0f), glm::vec3(wall + 4.0f, 1.5f, 2.0f)};
    for (const float side : {-1.0f, 1.0f})
        for (const float x : {1.0f, 2.5f, 4.0f})
            for (const float z : {-1.5f, 1.5f}) v.waypoints.push_back(glm::vec3(wall + side * x, 1.5f, z));
    return v;
}

TEST(WallLeaks, APartitionThinnerThanAVoxelSharesVoxelsOnceBothRoomsAreSeen) {
    // Off the voxel grid's boundaries (0.37 is no multiple of any level's voxel): the two rooms'
    // floors, ceilings and side walls meet in the voxels that span the partition. Baked, the dim
    // room of this pair read 60 times too bright through the cache.
    const Scene scene = twoRooms(0.37f, 1e-4f);
    const Tracer tracer(scene);
    const Views views = bothRooms(0.37f);
    const WallLeakReport report = findWallLeaks(tracer, HashGridParameters{}, views.cameras, views.waypoints);
    EXPECT_EQ(report.points, 16384u);
    EXPECT_GT(report.seen_sides, 15000u);  // the inner sides of both rooms
    EXPECT_GE(report.leaking_sides, kWallLeakSides);
    EXPECT_GE(report.share, kWallLeakShare);
    EXPECT_GT(report.voxel_size, 0.04f);
    EXPECT_LT(report.voxel_size, 0.2f);
    const std::string line = report.describe();
    EXPECT_NE(line.find("wall thinner than that"), std::string::npos) << line;
    EXPECT_NE(line.find("Give partitions a thickness of at least"), std::string::npos) << line;
}

TEST(WallLeaks, APartitionOnAVoxelBoundaryStillLeaksThroughTheKeysBias) {
    // At x = 0 every level's voxels meet at the partition, but SHaRC's keys add 1e-4 to positions
    // first: the bright room's last 0.1 mm is in the dim room's voxels (baked, +86% there).
    const Scene scene = twoRooms(0.0f, 1e-4f);
    const Tracer tracer(scene);
    const Views views = bothRooms(0.0f);
    const WallLeakReport report = findWallLeaks(tracer, HashGridParameters{}, views.cameras, views.waypoints);
    EXPECT_GE(report.leaking_sides, kWallLeakSides);
    EXPECT_NE(report.describe(), "");
}

TEST(WallLeaks, OneRoomSeenOrAThickWallOrALowFinIsNoLeak) {
    const HashGridParameters grid;
    {
        // The camera only in the second room: nothing deposits in the first.
        const Scene scene = twoRooms(0.37f, 1e-4f);
        const Tracer tracer(scene);
        Views views = bothRooms(0.37f);
        views.cameras.erase(views.cameras.begin());
        views.waypoints.erase(views.waypoints.begin(), views.waypoints.begin() + 6);
        const WallLeakReport report = findWallLeaks(tracer, grid, views.cameras, views.waypoints);
        EXPECT_EQ(report.leaking_sides, 0u);
        EXPECT_EQ(report.describe(), "");
    }
    {
        // A 10 cm wall: thicker than the voxels the cameras ask for beside it (measured: -0.2%).
        const Scene scene = twoRooms(0.37f, 0.1f);
        const Tracer tracer(scene);
        const Views views = bothRooms(0.37f);
        EXPECT_EQ(findWallLeaks(tracer, grid, views.cameras, views.waypoints).leaking_sides, 0u);
    }
    {
        // One room with a fin 0.1 mm thick and 30 cm tall across its floor: the floor either side
        // shares voxels, but the space above the fin sees both (a table leg, a low divider).
        Scene scene = twoRooms(0.37f, 1e-4f);
        scene.positions.resize(8);
        scene.triangles.resize(12);
        scene.triangle_materials.resize(12);
        const uint32_t base = uint32_t(scene.positions.size());
        for (const glm::vec3 p : {glm::vec3(-2.13f, 0.0f, -2.5f), glm::vec3(-2.13f, 0.3f, -2.5f),
                                  glm::vec3(-2.13f, 0.3f, 2.5f), glm::vec3(-2.13f, 0.0f, 2.5f)})
            scene.positions.push_back(p);
        scene.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
        scene.triangles.push_back(glm::uvec3(base, base + 2, base + 3));
        scene.triangle_materials.insert(scene.triangle_materials.end(), 2, 0u);
        scene.materials[0].double_sided = true;
        const Tracer tracer(scene);
        const std::vector<glm::vec3> cameras = {glm::vec3(-2.0f, 1.5f, 2.0f)};
        const std::vector<glm::vec3> waypoints = {glm::vec3(-3.5f, 1.5f, 0.0f), glm::vec3(-0.5f, 1.5f, 0.0f),
                                                  glm::vec3(-2.0f, 2.5f, -1.5f), glm::vec3(-2.0f, 2.5f, 1.5f)};
        EXPECT_EQ(findWallLeaks(tracer, grid, cameras, waypoints).leaking_sides, 0u);
    }
}

}  // namespace
}  // namespace sharcbake
