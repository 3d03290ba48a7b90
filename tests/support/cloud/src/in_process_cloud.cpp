#include "mrvs/test/in_process_cloud.h"

#include <cmath>

namespace mrvs::test {

InProcessCloud::InProcessCloud(std::shared_ptr<const map::QueryEngine> engine,
                               std::shared_ptr<const localise::Localiser> localiser)
    : engine_(std::move(engine)), localiser_(std::move(localiser)) {}

std::optional<edge::MapDescription> InProcessCloud::description() {
  if (!answer) return std::nullopt;
  const map::VoxelMap& m = engine_->map();
  return edge::MapDescription{m.origin, m.resolutions(), 0, offers_localisation()};
}

edge::MapReply InProcessCloud::query(const std::vector<voxel::RayQuery>& rays, TimestampNs /*stamp_ns*/,
                                     DurationNs timeout, bool want_normals) {
  edge::MapReply out;
  if (!answer) {
    out.rtt_ns = timeout;
    out.failure = "outage";
    return out;
  }
  out.answered = true;
  out.hits.resize(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const map::QueryResult r = engine_->query(rays[i]);
    if (r.status != map::QueryStatus::kHit) continue;
    out.hits[i].hit = true;
    out.hits[i].point = r.point;
    if (want_normals) {
      if (const auto n = engine_->surface_normal(r.level, r.point)) out.hits[i].normal = *n;
    }
  }
  return out;
}

StatusOr<std::size_t> InProcessCloud::send_localisation(const localisation::Request& request,
                                                        float quantum_m) {
  if (!offers_localisation()) return absl::UnavailableError("no localisation service");
  localisation::Request q = request;  // as the wire carries it
  for (Eigen::Vector3f& p : q.points) p = (p / quantum_m).array().round().matrix() * quantum_m;
  edge::LocalisationReply reply;
  reply.seq = request.seq;
  reply.result = localiser_->localise(q);
  reply.bytes_down = 244;
  reply.rtt_ns = static_cast<DurationNs>(reply.result.time_ms * 1e6);
  exchanges_.push_back({q, reply.result});
  const TimestampNs due = request.stamp_ns + (real_time_replies ? reply.rtt_ns : 0);
  due_.emplace_back(due, std::move(reply));
  return 104 + 6 * q.points.size();
}

std::vector<edge::LocalisationReply> InProcessCloud::poll_localisation() {
  std::vector<edge::LocalisationReply> out;
  while (!due_.empty() && (!real_time_replies || due_.front().first <= now_ns_)) {
    out.push_back(std::move(due_.front().second));
    due_.pop_front();
  }
  return out;
}

}  // namespace mrvs::test
