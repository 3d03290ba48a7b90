#pragma once
// Conversions between the project's types and the generated wire types (idl/mrvs_link.idl),
// and the checks both ends apply. Floats on the wire are map-local (relative to the origin
// in MapInfo).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"
#include "mrvs/voxel/ray_query.h"
#include "mrvs_link.h"

namespace mrvs::link {

/// What the edge learns about one ray.
struct RayAnswer {
  bool hit = false;
  Eigen::Vector3f point = Eigen::Vector3f::Zero();   ///< map-local, m (valid when hit)
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< unit surface normal; zero: none (or not asked)
};

/// The outcome of checking a request before answering it.
struct RequestCheck {
  wire::BatchStatus status = wire::STATUS_OK;
  std::uint32_t bad_ray_index = 0;  ///< first offending ray (status != OK)
  std::string detail;               ///< for logs
};

/// `want_normals`: the reply carries a surface normal per hit (wire protocol 2).
wire::RayQueryBatch encode_request(std::uint32_t client_id, std::uint64_t frame_seq, TimestampNs stamp_ns,
                                   const std::vector<voxel::RayQuery>& rays, bool want_normals = false);
voxel::RayQuery decode_ray(const wire::RayQuery& ray);

/// Rejects a request with more than max_rays rays, a non-finite value, a zero direction, a
/// negative distance, or a resolution that is not one of `resolutions` (voxel::find_level).
RequestCheck check_request(const wire::RayQueryBatch& request, std::size_t max_rays,
                           const std::vector<double>& resolutions);

/// The reply to `request`: `hits[i]` is the point of ray i, or nullopt. For status != OK,
/// `hits` is ignored and the reply carries no points. When the request wants normals,
/// `normals[i]` is ray i's surface normal (unit, or zero for none; missing entries: none).
wire::RayReplyBatch encode_reply(const wire::RayQueryBatch& request, const RequestCheck& check,
                                 const std::vector<std::optional<Eigen::Vector3f>>& hits,
                                 const std::vector<Eigen::Vector3f>& normals = {});

/// The answers of a reply to a request of `num_rays` rays: error when the reply's hit mask,
/// points and normals (none, or one per point) do not agree with each other or with
/// num_rays (a corrupt or foreign reply).
StatusOr<std::vector<RayAnswer>> decode_reply(const wire::RayReplyBatch& reply, std::size_t num_rays);

/// A unit normal as the wire's 3 x int16 (round(32767 n)); zero stays zero. decode_normal
/// returns the unit vector, or zero for an all-zero (or non-unit, corrupt) encoding.
std::array<std::int16_t, 3> encode_normal(const Eigen::Vector3f& n);
Eigen::Vector3f decode_normal(const std::array<std::int16_t, 3>& w);

/// Bytes of the hit mask for `num_rays` rays.
inline std::size_t hit_mask_bytes(std::size_t num_rays) { return (num_rays + 7) / 8; }

/// Map description sent by the cloud (transient local).
struct MapInfo {
  std::string map_id;
  Vec3d origin = Vec3d::Zero();  ///< map frame, m: wire floats are relative to it
  std::uint64_t checksum = 0;    ///< identifies the map content (changes when the map changes)
  std::vector<double> resolutions;
  std::uint32_t max_rays_per_batch = 0;
  std::uint32_t protocol_version = 0;
  /// The localisation protocol the cloud serves (LOCALISATION_PROTOCOL_VERSION), 0 for none.
  std::uint32_t localisation_protocol_version = 0;
};
wire::MapInfo encode_map_info(const MapInfo& info);
/// Error for another protocol version or an empty level list.
StatusOr<MapInfo> decode_map_info(const wire::MapInfo& info);

/// Human-readable name of a batch status.
const char* status_name(wire::BatchStatus status);

}  // namespace mrvs::link
