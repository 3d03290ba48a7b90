#pragma once
// Where the moving people walk (people.*): each crosses cam0's view at a drawn time of the
// window, and their truth files in sim0/.
#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/sim/generator.h"
#include "mrvs/sim/people.h"

namespace mrvs::sim {

/// options.count walkers. Walker i: at a time t drawn in the camera window, its path's
/// middle lies view_distance_m ahead of cam0 (along the optical axis, levelled, +- 0.5 m
/// sideways), the path runs across that direction, path_length_m long, clipped to the
/// scene's bounds less 0.5 m; it is there at t. A draw that comes within clearance_m (plus
/// half the person's diagonal, horizontally) of the body or a camera at any time of the
/// window, or whose clipped path is under 1 m, is drawn again (at most 50 times; then that
/// walker is left out and a warning logged). Same seed, same walkers.
StatusOr<std::vector<Walker>> plan_people(const PeopleOptions& options, const World& world,
                                          std::uint64_t seed);

/// sim0/people.yaml: every walker's path, speed, timing and size.
Status write_people_yaml(const std::filesystem::path& path, const std::vector<Walker>& walkers);

/// sim0/people.csv: "#timestamp [ns],cam0_pixels,cam1_pixels", pixels whose nearest hit is a person.
struct PeoplePixels {
  TimestampNs t_ns = 0;
  std::array<std::int64_t, 2> pixels{0, 0};
};
Status write_people_csv(const std::filesystem::path& path, const std::vector<PeoplePixels>& rows);
StatusOr<std::vector<PeoplePixels>> read_people_csv(const std::filesystem::path& path);

}  // namespace mrvs::sim
