#include "mrvs/link/localisation_codec.h"

#include <cmath>

#include <fmt/format.h>

namespace mrvs::link {
namespace {

using localisation::Status;

wire::LocalisationStatus to_wire(Status s) {
  switch (s) {
    case Status::kOk:
      return wire::LOCALISATION_OK;
    case Status::kTooLittleStructure:
      return wire::LOCALISATION_TOO_LITTLE_STRUCTURE;
    case Status::kAmbiguous:
      return wire::LOCALISATION_AMBIGUOUS;
    case Status::kOutsideMap:
      return wire::LOCALISATION_OUTSIDE_MAP;
    case Status::kBadRequest:
      return wire::LOCALISATION_BAD_REQUEST;
    case Status::kMapUnavailable:
      return wire::LOCALISATION_MAP_UNAVAILABLE;
    case Status::kServerError:
      return wire::LOCALISATION_SERVER_ERROR;
    case Status::kBusy:
      return wire::LOCALISATION_BUSY;
  }
  return wire::LOCALISATION_SERVER_ERROR;
}

std::optional<Status> from_wire(wire::LocalisationStatus s) {
  switch (s) {
    case wire::LOCALISATION_OK:
      return Status::kOk;
    case wire::LOCALISATION_TOO_LITTLE_STRUCTURE:
      return Status::kTooLittleStructure;
    case wire::LOCALISATION_AMBIGUOUS:
      return Status::kAmbiguous;
    case wire::LOCALISATION_OUTSIDE_MAP:
      return Status::kOutsideMap;
    case wire::LOCALISATION_BAD_REQUEST:
      return Status::kBadRequest;
    case wire::LOCALISATION_MAP_UNAVAILABLE:
      return Status::kMapUnavailable;
    case wire::LOCALISATION_SERVER_ERROR:
      return Status::kServerError;
    case wire::LOCALISATION_BUSY:
      return Status::kBusy;
  }
  return std::nullopt;
}

template <class A>
bool all_finite(const A& a) {
  for (const auto& x : a) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

template <std::size_t N>
Eigen::Matrix<double, N, 1> vec(const std::array<double, N>& a) {
  Eigen::Matrix<double, N, 1> v;
  for (std::size_t i = 0; i < N; ++i) v(static_cast<Eigen::Index>(i)) = a[i];
  return v;
}

Vec3d vec(const std::array<float, 3>& a) { return Vec3d(a[0], a[1], a[2]); }

/// The request's viewpoints; none when points were left out (the runs no longer line up) or a
/// count does not fit the wire.
void encode_viewpoints(const localisation::Request& q, bool all_points_sent, wire::LocalisationRequest* w) {
  if (!all_points_sent || q.viewpoints.size() > wire::MAX_VIEWPOINTS) return;
  for (const localisation::Viewpoint& v : q.viewpoints) {
    if (v.count > 65535 || !v.position.allFinite()) {
      w->viewpoints().clear();
      return;
    }
    wire::Viewpoint x;
    x.position({v.position.x(), v.position.y(), v.position.z()});
    x.count(static_cast<std::uint16_t>(v.count));
    w->viewpoints().push_back(x);
  }
}

}  // namespace

wire::LocalisationRequest encode_localisation_request(std::uint32_t client_id, const localisation::Request& q,
                                                      float quantum_m, std::size_t* dropped) {
  wire::LocalisationRequest w;
  w.request_seq(q.seq);
  w.stamp_ns(q.stamp_ns);
  w.anchor({q.anchor_o.x(), q.anchor_o.y(), q.anchor_o.z()});
  w.client_id(client_id);
  w.protocol_version(wire::LOCALISATION_PROTOCOL_VERSION);
  const Eigen::Vector3f g = q.gravity_o.cast<float>();
  w.gravity({g.x(), g.y(), g.z()});
  w.quantum_m(quantum_m);
  if (q.prior) {
    w.prior_centre({q.prior->centre_m.x(), q.prior->centre_m.y(), q.prior->centre_m.z()});
    w.prior_radius_m(static_cast<float>(q.prior->radius_m));
  } else {
    w.prior_centre({0.0, 0.0, 0.0});
    w.prior_radius_m(0.0f);
  }
  std::size_t left_out = 0;
  w.points().reserve(std::min<std::size_t>(q.points.size(), wire::MAX_SUBMAP_POINTS));
  const bool bright = q.brightness.size() == q.points.size();
  for (std::size_t i = 0; i < q.points.size(); ++i) {
    const Eigen::Vector3f& p = q.points[i];
    const Eigen::Array3f k = (p / quantum_m).array().round();
    if (!k.allFinite() || (k.abs() > 32767.0f).any() || w.points().size() >= wire::MAX_SUBMAP_POINTS) {
      ++left_out;
      continue;
    }
    wire::SubmapPoint s;
    s.xyz({static_cast<std::int16_t>(k.x()), static_cast<std::int16_t>(k.y()),
           static_cast<std::int16_t>(k.z())});
    w.points().push_back(s);
    if (bright) w.brightness().push_back(q.brightness[i]);
  }
  if (dropped) *dropped = left_out;
  encode_viewpoints(q, left_out == 0, &w);
  return w;
}

StatusOr<localisation::Request> decode_localisation_request(const wire::LocalisationRequest& w) {
  if (w.protocol_version() != wire::LOCALISATION_PROTOCOL_VERSION) {
    return absl::InvalidArgumentError(fmt::format("localisation protocol {}, this cloud speaks {}",
                                                  w.protocol_version(), wire::LOCALISATION_PROTOCOL_VERSION));
  }
  if (!(std::isfinite(w.quantum_m()) && w.quantum_m() > 0.0f)) {
    return absl::InvalidArgumentError(
        fmt::format("quantum_m must be a positive number, got {}", w.quantum_m()));
  }
  if (w.points().size() > wire::MAX_SUBMAP_POINTS) {
    return absl::InvalidArgumentError(
        fmt::format("{} submap points, at most {}", w.points().size(), wire::MAX_SUBMAP_POINTS));
  }
  if (!all_finite(w.anchor()) || !all_finite(w.gravity()) || !all_finite(w.prior_centre()) ||
      !std::isfinite(w.prior_radius_m())) {
    return absl::InvalidArgumentError("anchor, gravity and prior must be finite");
  }
  localisation::Request q;
  q.seq = w.request_seq();
  q.stamp_ns = w.stamp_ns();
  q.anchor_o = vec(w.anchor());
  q.gravity_o = vec(w.gravity());
  if (w.prior_radius_m() > 0.0f)
    q.prior = localisation::PriorRegion{vec(w.prior_centre()), w.prior_radius_m()};
  q.points.reserve(w.points().size());
  for (const wire::SubmapPoint& s : w.points()) {
    q.points.emplace_back(Eigen::Vector3f(s.xyz()[0], s.xyz()[1], s.xyz()[2]) * w.quantum_m());
  }
  if (!w.brightness().empty() && w.brightness().size() != w.points().size()) {
    return absl::InvalidArgumentError(
        fmt::format("{} brightness values for {} points (one per point, or none)", w.brightness().size(),
                    w.points().size()));
  }
  q.brightness.assign(w.brightness().begin(), w.brightness().end());
  if (w.viewpoints().size() > wire::MAX_VIEWPOINTS) {
    return absl::InvalidArgumentError(
        fmt::format("{} viewpoints, at most {}", w.viewpoints().size(), wire::MAX_VIEWPOINTS));
  }
  std::size_t seen = 0;
  for (const wire::Viewpoint& v : w.viewpoints()) {
    if (!all_finite(v.position())) return absl::InvalidArgumentError("viewpoints must be finite");
    q.viewpoints.push_back({Eigen::Vector3f(v.position()[0], v.position()[1], v.position()[2]), v.count()});
    seen += v.count();
  }
  if (seen > q.points.size()) {
    return absl::InvalidArgumentError(
        fmt::format("the viewpoints count {} points, the request has {}", seen, q.points.size()));
  }
  return q;
}

wire::LocalisationReply refuse_localisation(const wire::LocalisationRequest& request, Status status,
                                            const std::string& detail) {
  localisation::Result r;
  r.status = status;
  r.detail = detail;
  return encode_localisation_reply(request, r);
}

wire::LocalisationReply encode_localisation_reply(const wire::LocalisationRequest& request,
                                                  const localisation::Result& r) {
  wire::LocalisationReply w;
  w.request_seq(request.request_seq());
  w.client_id(request.client_id());
  w.protocol_version(wire::LOCALISATION_PROTOCOL_VERSION);
  w.status(to_wire(r.status));
  const Vec3d t = r.T_m_o.translation();
  const Quatd q = r.T_m_o.quaternion();
  w.translation({t.x(), t.y(), t.z()});
  w.rotation({q.x(), q.y(), q.z(), q.w()});
  std::array<float, 21> cov{};
  for (int i = 0, k = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j) cov[static_cast<std::size_t>(k++)] = static_cast<float>(r.covariance(i, j));
  }
  w.covariance(cov);
  w.fitness(static_cast<float>(r.fitness));
  w.rmse_m(static_cast<float>(r.rmse_m));
  w.ambiguity(static_cast<float>(r.ambiguity));
  w.hypotheses(static_cast<std::uint32_t>(std::max(r.hypotheses, 0)));
  w.time_ms(static_cast<float>(r.time_ms));
  w.detail(r.detail.substr(0, 200));
  return w;
}

StatusOr<localisation::Result> decode_localisation_reply(const wire::LocalisationReply& w) {
  if (w.protocol_version() != wire::LOCALISATION_PROTOCOL_VERSION) {
    return absl::DataLossError(fmt::format("localisation reply of protocol {}, this edge speaks {}",
                                           w.protocol_version(), wire::LOCALISATION_PROTOCOL_VERSION));
  }
  const std::optional<Status> status = from_wire(w.status());
  if (!status)
    return absl::DataLossError(fmt::format("localisation reply with unknown status {}", int(w.status())));
  localisation::Result r;
  r.status = *status;
  r.detail = w.detail();
  r.fitness = w.fitness();
  r.rmse_m = w.rmse_m();
  r.ambiguity = w.ambiguity();
  r.hypotheses = static_cast<int>(w.hypotheses());
  r.time_ms = w.time_ms();
  if (r.status != Status::kOk && r.status != Status::kAmbiguous && r.status != Status::kTooLittleStructure)
    return r;
  const Eigen::Vector4d q = vec(w.rotation());
  if (!all_finite(w.translation()) || !q.allFinite() || std::abs(q.norm() - 1.0) > 1e-6 ||
      !all_finite(w.covariance())) {
    return absl::DataLossError(
        fmt::format("localisation reply {}: non-finite pose or non-unit rotation", w.request_seq()));
  }
  r.T_m_o = SE3d(Quatd(q(3), q(0), q(1), q(2)), vec(w.translation()));
  for (int i = 0, k = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j)
      r.covariance(i, j) = r.covariance(j, i) = w.covariance()[static_cast<std::size_t>(k++)];
  }
  return r;
}

std::size_t payload_bytes(const wire::LocalisationRequest& request) {
  return 4 + wire::LocalisationRequest::getCdrSerializedSize(request);  // + encapsulation header
}

std::size_t payload_bytes(const wire::LocalisationReply& reply) {
  return 4 + wire::LocalisationReply::getCdrSerializedSize(reply);
}

}  // namespace mrvs::link
