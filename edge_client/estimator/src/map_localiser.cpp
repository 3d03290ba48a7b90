#include "mrvs/edge/map_localiser.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <Eigen/Cholesky>

#include "mrvs/core/hash.h"
#include "mrvs/edge/global_alignment.h"
#include "mrvs/geometry/angles.h"

namespace mrvs::edge {
namespace {

using localisation::Status;

std::uint64_t cell_key(const Vec3d& p, double cell) {
  const Eigen::Vector3i c = (p / cell).array().floor().cast<int>();
  return mix64((static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x())) << 42) ^
               (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y())) << 21) ^
               static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z())));
}

/// [position; yaw] covariance of `a` moved from its anchor to the map point x_m.
Eigen::Matrix4d covariance_at(const Alignment& a, const Vec3d& x_m) {
  return position_yaw_covariance(a.covariance, a.anchor_m, x_m);
}

}  // namespace

namespace {

/// The track's position at t_ns (linear between samples); nullopt outside its span (a few
/// milliseconds of slack at the ends: a fix stamped just after the newest frame).
std::optional<Vec3d> track_at(const std::deque<OdometrySample>& track, TimestampNs t_ns) {
  const DurationNs kSlack = from_seconds(0.05);
  if (track.empty() || t_ns < track.front().t_ns - kSlack || t_ns > track.back().t_ns + kSlack)
    return std::nullopt;
  auto after = std::lower_bound(track.begin(), track.end(), t_ns,
                                [](const OdometrySample& s, TimestampNs t) { return s.t_ns < t; });
  if (after == track.begin()) return track.front().p_o;
  if (after == track.end()) return track.back().p_o;
  const OdometrySample& before = *std::prev(after);
  const double u = after->t_ns == before.t_ns ? 1.0
                                              : static_cast<double>(t_ns - before.t_ns) /
                                                    static_cast<double>(after->t_ns - before.t_ns);
  return before.p_o + u * (after->p_o - before.p_o);
}

/// One fix's bound on the anchor: its position, the radius, and the body's odometry position then.
struct FixSphere {
  Vec3d g;
  double radius_m;
  Vec3d o;
};

}  // namespace

std::optional<localisation::PriorRegion> gnss_prior(const std::deque<io::GnssFix>& fixes,
                                                    const std::deque<OdometrySample>& track, TimestampNs t_ns,
                                                    const Vec3d& anchor_o, double window_s,
                                                    double lever_arm_m, const LocalisationOptions& o) {
  std::vector<FixSphere> spheres;
  for (const io::GnssFix& f : fixes) {
    if (f.t_ns > t_ns || f.t_ns < t_ns - from_seconds(window_s)) continue;
    const std::optional<Vec3d> o_f = track_at(track, f.t_ns);
    if (!o_f) continue;
    const double bound = o.gnss_sigmas * std::max(f.sigma_horizontal_m, f.sigma_vertical_m) + lever_arm_m;
    spheres.push_back({f.p_map, bound, *o_f});
  }
  if (spheres.empty()) return std::nullopt;
  // Two fixes agree when the body positions they allow can be as far apart as the track says.
  const auto agree = [](const FixSphere& a, const FixSphere& b) {
    return (a.g - b.g).norm() <= a.radius_m + b.radius_m + (a.o - b.o).norm();
  };
  std::optional<localisation::PriorRegion> best;
  for (const FixSphere& a : spheres) {
    std::size_t agreeing = 0;
    for (const FixSphere& b : spheres) agreeing += (&a != &b && agree(a, b)) ? 1 : 0;
    if (2 * agreeing < spheres.size() - 1) continue;  // contradicts most of the others
    best =
        tighter(best, localisation::PriorRegion{a.g, a.radius_m + (anchor_o - a.o).norm() + o.gnss_margin_m});
  }
  if (best) return best;
  // No majority (two fixes that contradict each other): a sphere around all of them.
  Vec3d centre = Vec3d::Zero();
  for (const FixSphere& a : spheres) centre += a.g / static_cast<double>(spheres.size());
  double radius = 0.0;
  for (const FixSphere& a : spheres)
    radius = std::max(radius, (a.g - centre).norm() + a.radius_m + (anchor_o - a.o).norm());
  return localisation::PriorRegion{centre, radius + o.gnss_margin_m};
}

std::optional<localisation::PriorRegion> restart_prior(const RunEnd& end, TimestampNs start_ns, double path_m,
                                                       const LocalisationOptions& o) {
  if (o.restart_radius_m <= 0.0) return std::nullopt;
  const double gap_s = std::max(0.0, to_seconds(start_ns - end.t_ns));
  return localisation::PriorRegion{
      end.p_m, end.carried_m + o.restart_radius_m + end.speed_mps * gap_s + std::max(0.0, path_m)};
}

std::optional<localisation::PriorRegion> tighter(const std::optional<localisation::PriorRegion>& a,
                                                 const std::optional<localisation::PriorRegion>& b) {
  if (!a) return b;
  if (!b) return a;
  return a->radius_m <= b->radius_m ? a : b;
}

MapLocaliser::MapLocaliser(const LocalisationOptions& options)
    : options_(options), window_s_(options.window_s) {}

void MapLocaliser::reset() {
  dense_.clear();
  tracks_.clear();
  pending_.reset();
  candidates_.clear();
  guesses_.clear();
  first_ns_.reset();
  next_request_ns_ = 0;
  last_dense_ns_ = 0;
  window_s_ = options_.window_s;
  requests_ = 0;
  tracking_ = false;
  refused_in_a_row_ = 0;
  confirmed_ = false;
  status_ = "restarted";
}

bool MapLocaliser::note_fix(bool applied) {
  refused_in_a_row_ = applied ? 0 : refused_in_a_row_ + 1;
  // Until a fix has been applied the lock is on probation: the first refusal doubts it.
  const bool on_probation = !confirmed_;
  confirmed_ = confirmed_ || applied;
  if (applied) {  // all is well: the next one in track_interval_s
    next_request_ns_ = std::max(next_request_ns_, last_sent_ns_ + from_seconds(options_.track_interval_s));
    return false;
  }
  if (options_.doubt_after_refusals <= 0 ||
      (!on_probation && refused_in_a_row_ < options_.doubt_after_refusals))
    return false;
  const int refused = refused_in_a_row_;
  reset();
  status_ = on_probation
                ? std::string(
                      "the first pose fix after the lock disagreed with it: the lock is doubted, "
                      "searching the map again")
                : fmt::format(
                      "{} pose fixes in a row disagreed with the filter: the lock is doubted, searching "
                      "the map again",
                      refused);
  return true;
}

void MapLocaliser::start_tracking(TimestampNs t_ns) {
  const std::string placed = status_;
  reset();
  tracking_ = true;
  first_ns_ = t_ns;
  // The first fix soon (as soon as window_s of new data is there): it checks the lock.
  next_request_ns_ = t_ns + from_seconds(std::min(options_.track_interval_s, options_.window_s));
  status_ = placed;
}

bool MapLocaliser::gathering(TimestampNs t_ns) const {
  if (!tracking_) return true;
  return options_.track_interval_s > 0.0 && t_ns >= next_request_ns_ - from_seconds(window_s_);
}

void MapLocaliser::add_points(TimestampNs t_ns, const std::vector<Vec3d>& points_o, const Vec3d& viewpoint_o,
                              const std::vector<std::uint8_t>& brightness) {
  if (!points_o.empty() && gathering(t_ns)) {
    dense_.push_back({Seen{t_ns, viewpoint_o}, points_o,
                      brightness.size() == points_o.size() ? brightness : std::vector<std::uint8_t>{}});
  }
  last_dense_ns_ = t_ns;
}

void MapLocaliser::set_track_point(FeatureId id, TimestampNs t_ns, const Vec3d& p_o, const Vec3d& viewpoint_o,
                                   float brightness) {
  if (options_.submap_source == "dense_stereo" || !gathering(t_ns)) return;
  TrackPoint& t = tracks_[id];
  t.seen = Seen{t_ns, viewpoint_o};
  t.p = p_o;
  if (brightness > 0.0f) t.brightness = brightness;
}

bool MapLocaliser::wants_dense(TimestampNs t_ns) const {
  return options_.submap_source != "tracks" && gathering(t_ns) &&
         (last_dense_ns_ == 0 || t_ns - last_dense_ns_ >= from_seconds(options_.dense_interval_s));
}

void MapLocaliser::forget_before(TimestampNs t_ns) {
  while (!dense_.empty() && dense_.front().seen.t_ns < t_ns) dense_.pop_front();
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    it = it->second.seen.t_ns < t_ns ? tracks_.erase(it) : std::next(it);
  }
}

std::optional<localisation::Request> MapLocaliser::build_request(TimestampNs t_ns,
                                                                 const Vec3d& anchor_o) const {
  const TimestampNs from = t_ns - from_seconds(window_s_);
  const DurationNs bucket = std::max<DurationNs>(1, from_seconds(options_.viewpoint_interval_s));
  // One point per cell (the mean of what fell in it), seen from its first point's viewpoint:
  // one per viewpoint_interval_s of the window.
  // A cell of dense points is kept only when min_dense_pairs stereo pairs put points in it:
  // a walking person or a passing car leaves its points in cells no other pair sees.
  struct Cell {
    Vec3d sum = Vec3d::Zero();
    int count = 0;
    std::int64_t view = 0;
    double brightness_sum = 0.0;  ///< over the points with a brightness
    int brightness_count = 0;
    int pairs = 0;  ///< dense pairs with points here (tracks count as enough)
    const void* last_pair = nullptr;
  };
  std::unordered_map<std::uint64_t, Cell> cells;
  std::vector<std::uint64_t> order;
  std::map<std::int64_t, Vec3d> views;
  // `pair`: the dense pair the point came from (nullptr: a track, multi-view already).
  auto add = [&](const Seen& seen, const Vec3d& p, float brightness, const void* pair) {
    if (seen.t_ns < from || !p.allFinite() || (p - anchor_o).norm() > options_.max_range_m) return;
    const std::int64_t view = (seen.t_ns - from) / bucket;
    views.try_emplace(view, seen.viewpoint_o);
    auto [it, fresh] = cells.try_emplace(cell_key(p, options_.voxel_m), Cell{Vec3d::Zero(), 0, view});
    if (fresh) order.push_back(it->first);
    if (pair == nullptr) {
      it->second.pairs = options_.min_dense_pairs;
    } else if (pair != it->second.last_pair) {
      ++it->second.pairs;
      it->second.last_pair = pair;
    }
    it->second.sum += p;
    ++it->second.count;
    if (brightness > 0.0f) {
      it->second.brightness_sum += brightness;
      ++it->second.brightness_count;
    }
  };
  for (const DensePoints& d : dense_) {
    for (std::size_t i = 0; i < d.points.size(); ++i)
      add(d.seen, d.points[i], d.brightness.empty() ? 0.0f : d.brightness[i], &d);
  }
  for (const auto& [id, t] : tracks_) add(t.seen, t.p, t.brightness, nullptr);
  order.erase(
      std::remove_if(order.begin(), order.end(),
                     [&](std::uint64_t key) { return cells.at(key).pairs < options_.min_dense_pairs; }),
      order.end());
  if (static_cast<int>(order.size()) < options_.min_points) return std::nullopt;
  // At most max_points, evenly spread, then grouped by viewpoint (the wire's order).
  const std::size_t n = order.size();
  const std::size_t m = std::min<std::size_t>(n, static_cast<std::size_t>(options_.max_points));
  std::map<std::int64_t, std::vector<const Cell*>> by_view;
  for (std::size_t i = 0; i < m; ++i) {
    const Cell& c = cells.at(order[i * n / m]);
    by_view[c.view].push_back(&c);
  }
  localisation::Request q;
  q.stamp_ns = t_ns;
  q.anchor_o = anchor_o;
  q.gravity_o = Vec3d(0, 0, -1);  // the filter's world frame is gravity-aligned
  q.points.reserve(m);
  q.brightness.reserve(m);
  for (const auto& [view, run] : by_view) {
    for (const Cell* c : run) {
      q.points.push_back((c->sum / c->count - anchor_o).cast<float>());
      const double b = c->brightness_count > 0 ? c->brightness_sum / c->brightness_count : 0.0;
      q.brightness.push_back(static_cast<std::uint8_t>(std::clamp(std::lround(b), 0L, 255L)));
    }
    q.viewpoints.push_back(
        {(views.at(view) - anchor_o).cast<float>(), static_cast<std::uint32_t>(run.size())});
  }
  return q;
}

std::optional<Alignment> MapLocaliser::step(TimestampNs t_ns, const Vec3d& anchor_o,
                                            const std::optional<localisation::PriorRegion>& prior,
                                            MapService& service, LocalisationFrameStats* stats) {
  if (!active()) return std::nullopt;
  if (!first_ns_) {
    first_ns_ = t_ns;
    next_request_ns_ = t_ns + from_seconds(options_.first_request_s);
  }
  forget_before(t_ns - from_seconds(options_.max_window_s));
  for (const LocalisationReply& reply : service.poll_localisation()) {
    if (!pending_ || reply.seq != pending_->seq)
      continue;  // stale (a request given up on, or before a restart)
    if (auto accepted = handle(reply, stats)) return accepted;
  }
  if (pending_ && Clock::now() - pending_->sent > std::chrono::duration<double>(options_.timeout_s)) {
    ++stats->timeouts;
    status_ = fmt::format("no localisation reply to request {} after {:.1f} s: asking again", pending_->seq,
                          options_.timeout_s);
    spdlog::warn("{}", status_);
    pending_.reset();
  }
  if (pending_ || t_ns < next_request_ns_) return std::nullopt;
  if (!service.offers_localisation()) {
    status_ = "waiting for the cloud's localisation service";
    return std::nullopt;
  }
  std::optional<localisation::Request> q = build_request(t_ns, anchor_o);
  if (!q) {
    status_ = fmt::format("gathering the submap (fewer than {} points)", options_.min_points);
    return std::nullopt;
  }
  q->seq = next_seq_++;
  q->prior = prior;
  auto sent = service.send_localisation(*q, static_cast<float>(options_.quantum_m));
  // Tracking: the next fix as soon as there is new data, unless this one is applied (note_fix).
  next_request_ns_ = t_ns + from_seconds(tracking_ ? std::min(options_.track_interval_s, options_.window_s)
                                                   : options_.interval_s);
  last_sent_ns_ = t_ns;
  if (!sent.ok()) {
    status_ = fmt::format("localisation request not sent: {}", std::string(sent.status().message()));
    return std::nullopt;
  }
  // The submap's data began at most window_s ago, and not before the run's first frame: a
  // window reaching back before it holds no more data (two answers in a run's first seconds
  // share it and are not independent).
  const TimestampNs from = std::max(t_ns - from_seconds(window_s_), *first_ns_);
  pending_ = Pending{q->seq, from, t_ns, anchor_o, Clock::now()};
  ++requests_;
  ++stats->requests;
  stats->bytes_up += *sent;
  stats->submap_points = static_cast<int>(q->points.size());
  status_ = fmt::format("{} request {} sent ({} points, {:.1f} s of data, {} B)",
                        tracking_ ? "pose fix" : "localisation", q->seq, q->points.size(), window_s_, *sent);
  return std::nullopt;
}

void MapLocaliser::refuse(const std::string& why) {
  window_s_ = std::min(options_.max_window_s, 1.5 * window_s_);
  status_ = why + fmt::format("; asking again with {:.1f} s of data", window_s_);
  spdlog::info("localisation: {}", status_);
}

std::optional<Alignment> MapLocaliser::handle(const LocalisationReply& reply, LocalisationFrameStats* stats) {
  const localisation::Result& r = reply.result;
  const Pending p = *pending_;
  pending_.reset();
  ++stats->replies;
  stats->bytes_down += reply.bytes_down;
  stats->rtt_ms = 1e-6 * static_cast<double>(reply.rtt_ns);
  stats->cloud_ms = r.time_ms;
  stats->reply = fmt::format("{}: {}", localisation::status_name(r.status), r.detail);
  if (tracking_) return handle_fix(reply, p);
  Alignment a{r.T_m_o, r.covariance, r.T_m_o * p.anchor_o, p.t_ns, p.from_ns, r.fitness, r.ambiguity};
  if (r.status != Status::kOk) {
    // A best guess: the cloud refined distinct poses and could not tell the best from a rival
    // (not a search that gave up, hypotheses 0).
    if (options_.guesses_confirm && r.status == Status::kAmbiguous && r.hypotheses > 0) {
      if (take_guess(a)) {
        std::vector<Alignment> agreeing = candidates_;
        agreeing.push_back(a);
        return accept(fuse(agreeing), fmt::format("an ok answer confirmed by answer {}'s best guess", p.seq),
                      stats);
      }
    }
    refuse(fmt::format("the cloud answered request {} '{}' ({})", p.seq, localisation::status_name(r.status),
                       r.detail));
    return std::nullopt;
  }
  if (r.ambiguity > options_.max_ambiguity) {
    refuse(
        fmt::format("answer {} is ambiguous ({:.2f} > {:.2f})", p.seq, r.ambiguity, options_.max_ambiguity));
    return std::nullopt;
  }
  if (!candidates_.empty() && !agree(candidates_.back(), a)) {
    // One of the two is wrong: start over from this one (the next answer, from new data, decides).
    candidates_.assign(1, a);
    status_ = fmt::format("answer {} disagrees with the previous one; asking again", p.seq);
    spdlog::info("localisation: {}", status_);
    return std::nullopt;
  }
  if (!candidates_.empty() && !independent(candidates_.back(), a)) {
    status_ = fmt::format(
        "answer {} ok and agrees, but from much the same data as the last one; waiting for new data", p.seq);
    spdlog::info("localisation: {}", status_);
    return std::nullopt;
  }
  candidates_.push_back(a);
  // The confirming answer should come from fresh data: back to the short submap.
  window_s_ = options_.window_s;
  const bool guessed = options_.guesses_confirm && confirming_guess(a) != nullptr;
  if (static_cast<int>(candidates_.size()) + (guessed ? 1 : 0) < options_.answers_needed) {
    status_ = fmt::format("answer {} ok (fitness {:.2f}, ambiguity {:.2f}); waiting for {} agreeing answers",
                          p.seq, r.fitness, r.ambiguity, options_.answers_needed);
    spdlog::info("localisation: {}", status_);
    return std::nullopt;
  }
  std::vector<Alignment> agreeing = candidates_;
  if (guessed) agreeing.push_back(*confirming_guess(a));
  return accept(fuse(agreeing),
                fmt::format("answer {} ({} agreeing{})", p.seq, candidates_.size(),
                            guessed ? ", and an earlier best guess" : ""),
                stats);
}

Alignment MapLocaliser::fuse(std::vector<Alignment> agreeing) const {
  std::sort(agreeing.begin(), agreeing.end(),
            [](const Alignment& a, const Alignment& b) { return a.t_ns < b.t_ns; });
  const Alignment& last = agreeing.back();
  // Each answer's [position; yaw] of the newest anchor, weighed by its covariance there (the
  // older ones' also by the agreement floors: the VIO's drift between the submaps).
  const Vec3d x_o = last.T_m_o.inverse() * last.anchor_m;
  Eigen::Matrix4d information = Eigen::Matrix4d::Zero();
  Eigen::Vector4d weighted = Eigen::Vector4d::Zero();
  for (std::size_t k = 0; k < agreeing.size(); ++k) {
    const Alignment& b = agreeing[k];
    Eigen::Vector4d z;
    z.head<3>() = b.T_m_o * x_o;
    z(3) = std::remainder(yaw_of(b.T_m_o) - yaw_of(last.T_m_o), 2.0 * kPi);
    Eigen::Matrix4d S = covariance_at(b, z.head<3>());
    if (k + 1 < agreeing.size()) {
      S.diagonal().head<3>().array() += options_.agree_floor_m * options_.agree_floor_m;
      S(3, 3) += std::pow(options_.agree_floor_deg * kDegToRad, 2);
    }
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(S);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || (ldlt.vectorD().array() <= 0.0).any())
      return last;  // a singular covariance: no weighing, the newest answer as it is
    information += ldlt.solve(Eigen::Matrix4d::Identity());
    weighted += ldlt.solve(z);
  }
  const Eigen::Matrix4d covariance = information.inverse();
  const Eigen::Vector4d mean = covariance * weighted;
  // The newest placement turned about its anchor by the fused yaw and moved to the fused position.
  const Vec3d x = last.anchor_m;
  const Mat3d Rz = Eigen::AngleAxisd(mean(3), Vec3d::UnitZ()).toRotationMatrix();
  Alignment f = last;
  f.T_m_o = SE3d(Quatd(Rz), mean.head<3>() - Rz * x) * last.T_m_o;
  f.anchor_m = f.T_m_o * x_o;
  f.covariance = Mat6d::Zero();
  const int idx[4] = {0, 1, 2, 5};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) f.covariance(idx[i], idx[j]) = covariance(i, j);
  }
  f.covariance = 0.5 * (f.covariance + f.covariance.transpose()).eval();
  for (const Alignment& b : agreeing) {
    f.from_ns = std::min(f.from_ns, b.from_ns);
    if (b.ambiguity < f.ambiguity) std::tie(f.fitness, f.ambiguity) = std::tie(b.fitness, b.ambiguity);
  }
  return f;
}

std::optional<Alignment> MapLocaliser::handle_fix(const LocalisationReply& reply, const Pending& p) {
  const localisation::Result& r = reply.result;
  if (r.status != Status::kOk || r.ambiguity > options_.max_ambiguity) {
    status_ = fmt::format("pose fix {} not used: the cloud answered '{}' ({})", p.seq,
                          localisation::status_name(r.status), r.detail);
    spdlog::debug("localisation: {}", status_);
    return std::nullopt;
  }
  status_ = fmt::format("pose fix {}: fitness {:.2f}, ambiguity {:.2f}", p.seq, r.fitness, r.ambiguity);
  return Alignment{r.T_m_o, r.covariance, r.T_m_o * p.anchor_o, p.t_ns, p.from_ns, r.fitness, r.ambiguity};
}

std::optional<Alignment> MapLocaliser::take_guess(const Alignment& guess) {
  constexpr std::size_t kKeptGuesses = 16;
  if (!candidates_.empty() && static_cast<int>(candidates_.size()) + 1 >= options_.answers_needed &&
      independent(candidates_.back(), guess) && agree(candidates_.back(), guess)) {
    return candidates_.back();
  }
  guesses_.push_back(guess);
  if (guesses_.size() > kKeptGuesses) guesses_.pop_front();
  return std::nullopt;
}

const Alignment* MapLocaliser::confirming_guess(const Alignment& a) const {
  for (auto it = guesses_.rbegin(); it != guesses_.rend(); ++it) {
    if (independent(*it, a) && agree(*it, a)) return &*it;
  }
  return nullptr;
}

std::optional<Alignment> MapLocaliser::accept(const Alignment& a, const std::string& how,
                                              LocalisationFrameStats* stats) {
  stats->accepted = true;
  status_ = fmt::format("localised by {}; fitness {:.2f}, ambiguity {:.2f}", how, a.fitness, a.ambiguity);
  return a;
}

bool MapLocaliser::independent(const Alignment& a, const Alignment& b) const {
  const double overlap = to_seconds(std::min(a.t_ns, b.t_ns) - std::max(a.from_ns, b.from_ns));
  const double shorter = to_seconds(std::min(a.t_ns - a.from_ns, b.t_ns - b.from_ns));
  return overlap <= options_.max_overlap * shorter;
}

bool MapLocaliser::agree(const Alignment& earlier, const Alignment& later) const {
  // Both place the later anchor (an odometry-frame point) in the map; VIO drift between the
  // two submaps is within the floors.
  const Vec3d x_later = later.anchor_m;
  const Vec3d x_earlier = earlier.T_m_o * (later.T_m_o.inverse() * later.anchor_m);
  Eigen::Vector4d d;
  d.head<3>() = x_earlier - x_later;
  d(3) = std::remainder(yaw_of(earlier.T_m_o) - yaw_of(later.T_m_o), 2.0 * kPi);
  Eigen::Matrix4d S = covariance_at(earlier, x_earlier) + covariance_at(later, x_later);
  S.diagonal().head<3>().array() += options_.agree_floor_m * options_.agree_floor_m;
  S(3, 3) += std::pow(options_.agree_floor_deg * kDegToRad, 2);
  const double m2 = d.dot(S.ldlt().solve(d));
  spdlog::debug("localisation agreement: {:.3f} m, {:.2f} deg, Mahalanobis^2 {:.1f}", d.head<3>().norm(),
                d(3) * kRadToDeg, m2);
  return std::isfinite(m2) && m2 <= kChi2Pose4;
}

}  // namespace mrvs::edge
