#pragma once
// The edge's side of map-based localisation (design/localisation.md; decision 7): until the
// odometry frame o is tied to the map frame m, the filter runs as plain VIO and this class
// gathers a submap in o (the triangulated feature tracks, or dense stereo), asks the cloud
// where it lies in the map, and decides which answer to trust:
//   - an answer must be "ok" with an ambiguity at most max_ambiguity;
//   - answers_needed answers from independent submaps (their data overlapping by at most
//     max_overlap) must agree (their T_m_o, within their covariances plus a floor) before the
//     newest is used: one wrong lock, or the same wrong lock twice from the same data, is not
//     enough;
//   - with guesses_confirm, an "ambiguous" answer's best pose (a real best guess: the cloud
//     refined rivals and could not tell them apart) may stand in for one of those answers when
//     it agrees with an "ok" one from independent data, before or after it: two submaps put the
//     same pose first and one of them tells it from every rival;
//   - the answer used is the agreeing answers combined (fuse(): weighed by their covariances);
//   - a refused or disagreeing answer makes the next submap longer (up to max_window_s);
//   - a request unanswered after timeout_s (wall clock) is given up and asked again.
// Once an answer is accepted and the state is in the map frame, with track_interval_s > 0 it
// tracks: it gathers a submap of window_s (now in the map frame) and asks again, within
// track_radius_m (plus the filter's own uncertainty) of where the filter is; each ok answer
// comes back from step() as a pose fix (apply_pose_fix: the filter's position and heading
// weighed against the answer's, gated), so the heading the rays cannot observe keeps being
// corrected. The first fix comes window_s after the lock (it checks it), and the next one
// track_interval_s after an applied fix, window_s after any other answer.
// `doubt_after_refusals` ok answers in a row that the filter's gate refuses mean the filter is
// not where it thinks (a wrong lock in a symmetric room, or a diverged heading): the lock is
// doubted and the localiser starts over (a search of the whole map, answers_needed agreeing
// answers), the filter running as plain VIO meanwhile. Until a first fix is applied the lock
// is on probation: one refusal doubts it. (Two refused fixes that agree with each other do not
// move the filter: a wrong answer along a wall repeats from one submap to the next.)
// Timing in the sensor clock (frame times) except the reply timeout (steady clock).
#include <chrono>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/edge/feature_observation.h"
#include "mrvs/edge/map_service.h"
#include "mrvs/io/types.h"
#include "mrvs/localisation/types.h"

namespace mrvs::edge {

struct LocalisationOptions : config::OptionsEquality<LocalisationOptions> {
  std::string submap_source = "both";  ///< tracks | dense_stereo | both
  double first_request_s = 1.0;        ///< after initialisation, s
  double window_s = 1.5;               ///< the submap holds the points of this long, s
  double max_window_s = 6.0;           ///< ... growing to this after refusals, s
  double interval_s = 1.0;             ///< between requests (after the last reply), s
  double timeout_s = 3.0;              ///< a request unanswered this long (wall clock) is asked again, s
  double max_range_m = 8.0;            ///< submap points farther from the anchor are left out, m
  double voxel_m = 0.04;               ///< one submap point per cell of this size, m
  int max_points = 6000;               ///< submap points sent at most (<= 9000, 7 B each)
  int min_points = 150;                ///< fewer: wait for more
  double quantum_m = 0.005;            ///< wire quantisation of the points, m
  double max_ambiguity = 0.8;          ///< answers more ambiguous are refused
  int answers_needed = 2;              ///< agreeing answers before one is used
  bool guesses_confirm = false;        ///< an ambiguous answer's best pose may be one of them (not alone)
  double max_overlap = 0.5;            ///< share of a submap's time span another may share and count
  double agree_floor_m = 0.05;         ///< agreement: covariance plus this, m
  double agree_floor_deg = 0.5;        ///< ... and this, deg
  double dense_interval_s = 0.25;      ///< dense_stereo: one stereo pair per this, s
  int min_dense_pairs = 1;             ///< a cell of dense points only when this many pairs put points in it
  double viewpoint_interval_s = 0.25;  ///< points seen within this share one viewpoint, s
  double gnss_sigmas = 3.0;            ///< prior region: this many GNSS sigmas ...
  double gnss_margin_m = 2.0;          ///< ... plus the antenna lever arm plus this, m
  double restart_radius_m = 1.0;  ///< after a restart from a placed pose: searched near its end, m (0: off)
  double track_interval_s = 0.0;  ///< in the map frame: a pose fix asked every this long, s (0: none)
  double track_radius_m = 1.0;    ///< ... searched within this of the filter (plus 3 sigma), m
  double fix_floor_m = 0.0;       ///< pose fixes: the filter's position trusted no better than this, m
  double fix_floor_deg = 0.0;     ///< ... and its heading, deg
  int doubt_after_refusals = 3;   ///< ok pose fixes in a row the gate refuses: the lock is doubted (0: never)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("submap_source", submap_source, one_of({"tracks", "dense_stereo", "both"}),
      "submap points: tracks | dense_stereo");
    v("first_request_s", first_request_s, in_range(0.0, 600.0), "first request after initialisation, s");
    v("window_s", window_s, in_range(0.1, 600.0), "submap time span, s");
    v("max_window_s", max_window_s, in_range(0.1, 600.0), "longest submap time span, s");
    v("interval_s", interval_s, in_range(0.0, 600.0), "between requests, s");
    v("timeout_s", timeout_s, in_range(0.01, 600.0), "unanswered request timeout (wall clock), s");
    v("max_range_m", max_range_m, in_range(0.1, 10000.0), "submap radius around the anchor, m");
    v("voxel_m", voxel_m, in_range(0.001, 100.0), "submap thinning cell, m");
    v("max_points", max_points, in_range(10, 9000), "submap points sent at most");
    v("min_points", min_points, in_range(10, 10000), "submap points needed to ask");
    v("quantum_m", quantum_m, in_range(0.0001, 1.0), "wire quantisation of the points, m");
    v("max_ambiguity", max_ambiguity, in_range(0.0, 1.0), "most ambiguous answer accepted");
    v("answers_needed", answers_needed, in_range(1, 10), "agreeing answers before one is used");
    v("guesses_confirm", guesses_confirm, any(),
      "an ambiguous answer's best pose may stand in for one agreeing answer (never alone)");
    v("max_overlap", max_overlap, in_range(0.0, 1.0), "time share two agreeing submaps may have in common");
    v("agree_floor_m", agree_floor_m, in_range(0.0, 100.0), "agreement floor, m");
    v("agree_floor_deg", agree_floor_deg, in_range(0.0, 180.0), "agreement floor, deg");
    v("dense_interval_s", dense_interval_s, in_range(0.01, 100.0), "dense stereo: time between pairs, s");
    v("min_dense_pairs", min_dense_pairs, in_range(1, 100),
      "a submap cell of dense stereo points needs points from this many pairs (what moves stays in none)");
    v("viewpoint_interval_s", viewpoint_interval_s, in_range(0.01, 100.0),
      "points seen within this share one viewpoint (<= 64 per request), s");
    v("gnss_sigmas", gnss_sigmas, in_range(0.0, 100.0), "prior radius in GNSS sigmas");
    v("gnss_margin_m", gnss_margin_m, in_range(0.0, 10000.0), "prior radius margin, m");
    v("restart_radius_m", restart_radius_m, in_range(0.0, 10000.0),
      "after a filter restart from a pose placed in the map: the new run is searched within this of where "
      "the "
      "last one ended, plus its speed times the gap, plus the path since, m (0: anywhere)");
    v("track_interval_s", track_interval_s, in_range(0.0, 3600.0),
      "once in the map frame: a localisation request every this long, its answer a pose fix, s (0: none)");
    v("track_radius_m", track_radius_m, in_range(0.01, 10000.0),
      "pose fixes: searched within this of the filter's position (plus 3 sigma), m");
    v("fix_floor_m", fix_floor_m, in_range(0.0, 100.0),
      "pose fixes: the filter's own position is trusted no better than this (sigma), m");
    v("fix_floor_deg", fix_floor_deg, in_range(0.0, 180.0),
      "pose fixes: the filter's own heading is trusted no better than this (sigma), deg");
    v("doubt_after_refusals", doubt_after_refusals, in_range(0, 1000),
      "ok pose fixes in a row the filter's gate refuses before the lock is doubted and searched again (0: "
      "never)");
  }
};

/// The IMU position in the odometry frame at one time: the track gnss_prior reads.
struct OdometrySample {
  TimestampNs t_ns = 0;
  Vec3d p_o = Vec3d::Zero();
};

/// The prior region from GNSS fixes (antenna positions, map frame) for the body at anchor_o
/// (odometry frame) at t_ns. A fix at t_f puts the antenna within gnss_sigmas times its larger
/// sigma, so the body within that plus the lever arm (the heading that would turn it is not
/// known yet); the body has since moved |anchor_o - p_o(t_f)| (the track interpolated at t_f; the
/// odometry-to-map transform keeps distances whatever its heading), so each fix of the last
/// window_s that the track covers bounds the anchor by a sphere. A fix whose sphere cannot meet
/// those of most others is an outlier (multipath) and dropped; of the rest the smallest sphere
/// is returned, its radius plus gnss_margin_m. nullopt without such a fix.
std::optional<localisation::PriorRegion> gnss_prior(const std::deque<io::GnssFix>& fixes,
                                                    const std::deque<OdometrySample>& track, TimestampNs t_ns,
                                                    const Vec3d& anchor_o, double window_s,
                                                    double lever_arm_m, const LocalisationOptions& options);

/// Where the previous filter run ended, placed in the map (map frame), and how fast it moved.
/// A run that ended unplaced after such a restart hands on its own start's region: the centre
/// stays, the radius it had reached is carried (carried_m).
struct RunEnd {
  Vec3d p_m = Vec3d::Zero();
  double speed_mps = 0.0;
  TimestampNs t_ns = 0;
  double carried_m = 0.0;
};

/// The prior region of a run that began at start_ns after a filter restart from `end`: centred
/// where the last run ended, the radius restart_radius_m plus the speed times the gap (the motion
/// the restart lost) plus path_m, the new run's path length since (its heading in the map is not
/// known, so any direction), plus end.carried_m. nullopt when restart_radius_m is 0.
std::optional<localisation::PriorRegion> restart_prior(const RunEnd& end, TimestampNs start_ns, double path_m,
                                                       const LocalisationOptions& options);

/// The smaller of two prior regions (either may be missing).
std::optional<localisation::PriorRegion> tighter(const std::optional<localisation::PriorRegion>& a,
                                                 const std::optional<localisation::PriorRegion>& b);

/// An accepted answer: the odometry frame in the map.
struct Alignment {
  SE3d T_m_o;
  Mat6d covariance = Mat6d::Zero();  ///< [rho; phi] about anchor_m (mrvs/localisation/types.h)
  Vec3d anchor_m = Vec3d::Zero();
  TimestampNs t_ns = 0;     ///< anchor time of the submap
  TimestampNs from_ns = 0;  ///< its data began here
  double fitness = 0.0;
  double ambiguity = 0.0;
};

/// What localisation did in one frame.
struct LocalisationFrameStats {
  int requests = 0;
  std::size_t bytes_up = 0;
  int replies = 0;
  std::size_t bytes_down = 0;
  int submap_points = 0;  ///< of the request sent this frame
  double rtt_ms = 0.0;    ///< of the reply taken this frame
  double cloud_ms = 0.0;  ///< the cloud's registration time of that reply
  int timeouts = 0;
  std::string reply;      ///< "<status>: <detail>" of the reply taken, if any
  bool accepted = false;  ///< the answer that placed the filter in the map frame
  int fixes_applied = 0;  ///< tracking: answers applied as pose fixes
  int fixes_refused = 0;  ///< tracking: ok answers the filter's gate refused
  bool doubted = false;   ///< the lock was doubted this frame (doubt_after_refusals): searching again
};

class MapLocaliser {
 public:
  explicit MapLocaliser(const LocalisationOptions& options);

  /// Forgets the submap, the candidates and the request in flight (a filter restart: a new
  /// odometry frame).
  void reset();
  /// Points seen at t_ns (odometry frame) from the camera centre `viewpoint_o`, e.g. one dense
  /// stereo pair, with their image brightness (one per point, 1-255, 0: not known; or empty).
  void add_points(TimestampNs t_ns, const std::vector<Vec3d>& points_o, const Vec3d& viewpoint_o,
                  const std::vector<std::uint8_t>& brightness = {});
  /// A feature's latest position estimate (odometry frame) at t_ns, seen from `viewpoint_o`;
  /// replaces its earlier one. brightness: its image brightness now (0-255; <= 0: not seen
  /// now, the earlier value stays).
  void set_track_point(FeatureId id, TimestampNs t_ns, const Vec3d& p_o, const Vec3d& viewpoint_o,
                       float brightness = 0.0f);
  /// Whether a dense stereo pair at t_ns is wanted (dense_stereo source, dense_interval_s,
  /// and gathering()).
  bool wants_dense(TimestampNs t_ns) const;
  /// Whether points seen at t_ns are wanted: always until the lock; when tracking, in the
  /// window_s before the next request.
  bool gathering(TimestampNs t_ns) const;
  /// After the accepted answer at t_ns placed the state in the map frame: forget the
  /// acquisition and track (pose fixes every track_interval_s; nothing when it is 0).
  void start_tracking(TimestampNs t_ns);
  /// Whether step() still has work: before the lock, or tracking with track_interval_s > 0.
  bool active() const { return !tracking_ || options_.track_interval_s > 0.0; }
  bool tracking() const { return tracking_; }
  /// Tracking: whether the filter applied the pose fix step() returned. True when the lock is
  /// doubted: after doubt_after_refusals refusals in a row, or one before any fix was applied
  /// since the lock (probation); the localiser is then reset (it searches the whole map again;
  /// the caller leaves the map frame). 0 doubt_after_refusals: never.
  bool note_fix(bool applied);

  /// One frame: takes replies, decides, maybe sends the next request (anchored at the IMU
  /// position anchor_o at t_ns, with the prior region if any). The accepted alignment, once;
  /// when tracking, each ok answer (a pose fix, in the map frame).
  std::optional<Alignment> step(TimestampNs t_ns, const Vec3d& anchor_o,
                                const std::optional<localisation::PriorRegion>& prior, MapService& service,
                                LocalisationFrameStats* stats);

  /// The submap request it would send now (for tests and diagnostics); nullopt with too few points.
  std::optional<localisation::Request> build_request(TimestampNs t_ns, const Vec3d& anchor_o) const;
  /// The last decision in words ("waiting for 2 agreeing answers (1 so far)", ...).
  const std::string& status() const { return status_; }
  /// Requests sent since the last reset.
  int requests() const { return requests_; }

 private:
  using Clock = std::chrono::steady_clock;
  struct Pending {
    std::uint64_t seq = 0;
    TimestampNs from_ns = 0;  ///< the submap's data: [from_ns, t_ns]
    TimestampNs t_ns = 0;
    Vec3d anchor_o = Vec3d::Zero();
    Clock::time_point sent;
  };
  std::optional<Alignment> handle(const LocalisationReply& reply, LocalisationFrameStats* stats);
  /// Tracking: an ok, unambiguous answer is a pose fix.
  std::optional<Alignment> handle_fix(const LocalisationReply& reply, const Pending& p);
  /// An ambiguous answer with a best guess: the ok candidate it confirms, if any (else kept).
  std::optional<Alignment> take_guess(const Alignment& guess);
  /// A guess from independent data that agrees with `a`, if any.
  const Alignment* confirming_guess(const Alignment& a) const;
  std::optional<Alignment> accept(const Alignment& a, const std::string& how, LocalisationFrameStats* stats);
  /// The agreeing answers as one: their placements of the newest anchor (position and yaw)
  /// weighed by their covariances (older ones' widened by the agreement floors), and the
  /// combined covariance; the newest answer as it is when a covariance is singular.
  Alignment fuse(std::vector<Alignment> agreeing) const;
  bool agree(const Alignment& earlier, const Alignment& later) const;
  /// Their submaps share at most max_overlap of the shorter one's time span.
  bool independent(const Alignment& a, const Alignment& b) const;
  void refuse(const std::string& why);
  void forget_before(TimestampNs t_ns);

  LocalisationOptions options_;
  struct Seen {
    TimestampNs t_ns = 0;
    Vec3d viewpoint_o = Vec3d::Zero();
  };
  struct DensePoints {
    Seen seen;
    std::vector<Vec3d> points;
    std::vector<std::uint8_t> brightness;  ///< one per point, or empty
  };
  struct TrackPoint {
    Seen seen;
    Vec3d p = Vec3d::Zero();
    float brightness = 0.0f;  ///< 0: not known
  };
  std::deque<DensePoints> dense_;
  std::map<FeatureId, TrackPoint> tracks_;
  std::optional<Pending> pending_;
  std::vector<Alignment> candidates_;  ///< agreeing answers so far
  std::deque<Alignment> guesses_;      ///< best poses of the latest ambiguous answers (guesses_confirm)
  std::optional<TimestampNs> first_ns_;
  TimestampNs next_request_ns_ = 0;
  TimestampNs last_dense_ns_ = 0;
  double window_s_;
  std::uint64_t next_seq_ = 1;
  int requests_ = 0;
  std::string status_ = "not started";
  bool tracking_ = false;  ///< placed in the map frame: answers are pose fixes
  int refused_in_a_row_ = 0;
  bool confirmed_ = false;        ///< a pose fix has been applied since the lock (else: on probation)
  TimestampNs last_sent_ns_ = 0;  ///< anchor time of the last request sent
};

}  // namespace mrvs::edge
