#include "mrvs/link/codec.h"

#include <algorithm>
#include <bitset>
#include <cmath>

#include <fmt/format.h>

#include "mrvs/voxel/resolution.h"

namespace mrvs::link {
namespace {

bool finite(const std::array<float, 3>& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

RequestCheck reject(wire::BatchStatus status, std::uint32_t index, std::string detail) {
  return RequestCheck{status, index, std::move(detail)};
}

}  // namespace

wire::RayQueryBatch encode_request(std::uint32_t client_id, std::uint64_t frame_seq, TimestampNs stamp_ns,
                                   const std::vector<voxel::RayQuery>& rays, bool want_normals) {
  wire::RayQueryBatch batch;
  batch.want_normals(want_normals);
  batch.client_id(client_id);
  batch.frame_seq(frame_seq);
  batch.stamp_ns(stamp_ns);
  batch.rays().resize(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    wire::RayQuery& w = batch.rays()[i];
    const voxel::RayQuery& r = rays[i];
    w.origin({r.origin.x(), r.origin.y(), r.origin.z()});
    w.initial_distance(r.initial_distance);
    w.direction({r.direction.x(), r.direction.y(), r.direction.z()});
    w.resolution(r.resolution);
  }
  return batch;
}

voxel::RayQuery decode_ray(const wire::RayQuery& w) {
  voxel::RayQuery r;
  r.origin = Eigen::Vector3f(w.origin()[0], w.origin()[1], w.origin()[2]);
  r.initial_distance = w.initial_distance();
  r.direction = Eigen::Vector3f(w.direction()[0], w.direction()[1], w.direction()[2]);
  r.resolution = w.resolution();
  return r;
}

RequestCheck check_request(const wire::RayQueryBatch& request, std::size_t max_rays,
                           const std::vector<double>& resolutions) {
  const auto& rays = request.rays();
  if (rays.size() > max_rays) {
    return reject(wire::STATUS_TOO_MANY_RAYS, static_cast<std::uint32_t>(max_rays),
                  fmt::format("{} rays, at most {} per batch", rays.size(), max_rays));
  }
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const wire::RayQuery& r = rays[i];
    const auto index = static_cast<std::uint32_t>(i);
    if (!finite(r.origin()) || !finite(r.direction()) || !std::isfinite(r.initial_distance()) ||
        !std::isfinite(r.resolution())) {
      return reject(wire::STATUS_INVALID_RAY, index, fmt::format("ray {}: non-finite value", i));
    }
    const auto& d = r.direction();
    if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) {
      return reject(wire::STATUS_INVALID_RAY, index, fmt::format("ray {}: zero direction", i));
    }
    if (r.initial_distance() < 0.0f) {
      return reject(wire::STATUS_INVALID_RAY, index, fmt::format("ray {}: negative distance", i));
    }
    if (!voxel::find_level(resolutions, r.resolution())) {
      return reject(wire::STATUS_UNKNOWN_RESOLUTION, index,
                    fmt::format("ray {}: resolution {} m is not a map level", i, r.resolution()));
    }
  }
  return RequestCheck{};
}

wire::RayReplyBatch encode_reply(const wire::RayQueryBatch& request, const RequestCheck& check,
                                 const std::vector<std::optional<Eigen::Vector3f>>& hits,
                                 const std::vector<Eigen::Vector3f>& normals) {
  wire::RayReplyBatch reply;
  reply.client_id(request.client_id());
  reply.frame_seq(request.frame_seq());
  reply.status(check.status);
  reply.bad_ray_index(check.bad_ray_index);
  if (check.status != wire::STATUS_OK) return reply;
  reply.hit_mask().assign(hit_mask_bytes(hits.size()), 0);
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i]) continue;
    reply.hit_mask()[i / 8] = static_cast<std::uint8_t>(reply.hit_mask()[i / 8] | (1u << (i % 8)));
    wire::MapPoint point;
    point.position({hits[i]->x(), hits[i]->y(), hits[i]->z()});
    reply.points().push_back(point);
    if (!request.want_normals()) continue;
    wire::SurfaceNormal normal;
    normal.normal(encode_normal(i < normals.size() ? normals[i] : Eigen::Vector3f::Zero()));
    reply.normals().push_back(normal);
  }
  return reply;
}

StatusOr<std::vector<RayAnswer>> decode_reply(const wire::RayReplyBatch& reply, std::size_t num_rays) {
  if (reply.hit_mask().size() != hit_mask_bytes(num_rays)) {
    return absl::DataLossError(fmt::format("reply {}: hit mask of {} bytes for {} rays", reply.frame_seq(),
                                           reply.hit_mask().size(), num_rays));
  }
  std::size_t set = 0;
  for (std::size_t b = 0; b < reply.hit_mask().size(); ++b)
    set += std::bitset<8>(reply.hit_mask()[b]).count();
  const bool padding_clear = num_rays % 8 == 0 || (reply.hit_mask().back() >> (num_rays % 8)) == 0;
  if (set != reply.points().size() || !padding_clear) {
    return absl::DataLossError(
        fmt::format("reply {}: {} hit bits but {} points", reply.frame_seq(), set, reply.points().size()));
  }
  if (!reply.normals().empty() && reply.normals().size() != set) {
    return absl::DataLossError(
        fmt::format("reply {}: {} normals for {} points", reply.frame_seq(), reply.normals().size(), set));
  }
  std::vector<RayAnswer> answers(num_rays);
  std::size_t next = 0;
  for (std::size_t i = 0; i < num_rays; ++i) {
    if ((reply.hit_mask()[i / 8] >> (i % 8) & 1u) == 0) continue;
    if (!reply.normals().empty()) answers[i].normal = decode_normal(reply.normals()[next].normal());
    const auto& p = reply.points()[next++].position();
    answers[i].hit = true;
    answers[i].point = Eigen::Vector3f(p[0], p[1], p[2]);
  }
  return answers;
}

std::array<std::int16_t, 3> encode_normal(const Eigen::Vector3f& n) {
  std::array<std::int16_t, 3> out{0, 0, 0};
  const float norm = n.norm();
  if (!(norm > 0.5f) || !n.allFinite()) return out;
  for (int k = 0; k < 3; ++k)
    out[static_cast<std::size_t>(k)] =
        static_cast<std::int16_t>(std::lround(32767.0f * std::clamp(n[k] / norm, -1.0f, 1.0f)));
  return out;
}

Eigen::Vector3f decode_normal(const std::array<std::int16_t, 3>& w) {
  const Eigen::Vector3f n(w[0], w[1], w[2]);
  const float norm = n.norm();
  // A unit vector encodes to a norm of 32767 within rounding: anything else is not one.
  if (!(std::abs(norm - 32767.0f) < 4.0f)) return Eigen::Vector3f::Zero();
  return n / norm;
}

wire::MapInfo encode_map_info(const MapInfo& info) {
  wire::MapInfo w;
  w.map_id(info.map_id.substr(0, 64));
  w.origin({info.origin.x(), info.origin.y(), info.origin.z()});
  w.map_checksum(info.checksum);
  w.protocol_version(wire::WIRE_PROTOCOL_VERSION);
  w.rays_per_batch_limit(info.max_rays_per_batch);
  for (double r : info.resolutions) w.resolutions().push_back(static_cast<float>(r));
  w.localisation_version(info.localisation_protocol_version);
  return w;
}

StatusOr<MapInfo> decode_map_info(const wire::MapInfo& w) {
  if (w.protocol_version() != wire::WIRE_PROTOCOL_VERSION) {
    return absl::FailedPreconditionError(
        fmt::format("the cloud speaks wire protocol {}, this edge speaks {}: use matching builds",
                    w.protocol_version(), wire::WIRE_PROTOCOL_VERSION));
  }
  if (w.resolutions().empty()) return absl::DataLossError("map info without levels");
  MapInfo info;
  info.map_id = w.map_id();
  info.origin = Vec3d(w.origin()[0], w.origin()[1], w.origin()[2]);
  info.checksum = w.map_checksum();
  info.max_rays_per_batch = w.rays_per_batch_limit();
  info.protocol_version = w.protocol_version();
  info.localisation_protocol_version = w.localisation_version();
  for (float r : w.resolutions()) info.resolutions.push_back(static_cast<double>(r));
  return info;
}

const char* status_name(wire::BatchStatus status) {
  switch (status) {
    case wire::STATUS_OK:
      return "ok";
    case wire::STATUS_TOO_MANY_RAYS:
      return "too many rays";
    case wire::STATUS_INVALID_RAY:
      return "invalid ray";
    case wire::STATUS_UNKNOWN_RESOLUTION:
      return "unknown resolution";
    case wire::STATUS_MAP_UNAVAILABLE:
      return "map unavailable";
    case wire::STATUS_SERVER_ERROR:
      return "server error";
  }
  return "unknown status";
}

}  // namespace mrvs::link
