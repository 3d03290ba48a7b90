// Format-independent parts of the dataset readers: summaries, stereo pairing, factory.
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "mrvs/io/dataset.h"
#include "mrvs/io/image.h"

namespace mrvs::io {
namespace {

DurationNs median_period(const std::vector<TimestampNs>& t_ns) {
  if (t_ns.size() < 2) return 0;
  std::vector<DurationNs> periods(t_ns.size() - 1);
  for (std::size_t i = 1; i < t_ns.size(); ++i) periods[i - 1] = t_ns[i] - t_ns[i - 1];
  const auto mid = periods.begin() + static_cast<std::ptrdiff_t>(periods.size() / 2);
  std::nth_element(periods.begin(), mid, periods.end());
  return *mid;
}

std::vector<TimestampNs> stamps(const std::vector<ImageRecord>& images) {
  std::vector<TimestampNs> t;
  t.reserve(images.size());
  for (const ImageRecord& r : images) t.push_back(r.t_ns);
  return t;
}

std::string format_ms(DurationNs d_ns) { return fmt::format("{:.3f} ms", to_seconds(d_ns) * 1e3); }

}  // namespace

StreamSummary summarize_stream(const std::string& name, const std::vector<TimestampNs>& t_ns,
                               double nominal_rate_hz) {
  StreamSummary s;
  s.name = name;
  s.count = t_ns.size();
  if (t_ns.empty()) return s;
  s.first_ns = t_ns.front();
  s.last_ns = t_ns.back();
  if (t_ns.size() < 2) return s;
  s.rate_hz = static_cast<double>(t_ns.size() - 1) / s.span_s();
  s.median_period_ns = median_period(t_ns);
  s.nominal_period_ns = nominal_rate_hz > 0.0 ? from_seconds(1.0 / nominal_rate_hz) : s.median_period_ns;
  for (std::size_t i = 1; i < t_ns.size(); ++i) {
    const DurationNs period = t_ns[i] - t_ns[i - 1];
    s.largest_period_ns = std::max(s.largest_period_ns, period);
    if (period > 2 * s.nominal_period_ns) {
      if (s.gaps.size() < StreamSummary::kMaxListedGaps) s.gaps.push_back(TimeGap{t_ns[i - 1], t_ns[i]});
      ++s.gap_count;
    }
  }
  return s;
}

std::string StreamSummary::describe() const {
  if (count == 0) return fmt::format("{}: no samples", name);
  std::string text = fmt::format("{}: {} samples, {} .. {} s ({:.3f} s)", name, count,
                                 format_seconds(first_ns), format_seconds(last_ns), span_s());
  if (count < 2) return text;
  text += fmt::format(", {:.2f} Hz, median period {}", rate_hz, format_ms(median_period_ns));
  if (gap_count == 0) return text + ", no gaps";
  text += fmt::format(", {} gaps longer than 2 x {} (largest {}; first at {} s)", gap_count,
                      format_ms(nominal_period_ns), format_ms(largest_period_ns),
                      format_seconds(gaps.front().from_ns));
  return text;
}

std::string DatasetSummary::describe() const {
  std::string text = fmt::format("{} sequence '{}' ({})\n", format, name, root.string());
  for (const StreamSummary& cam : cameras) text += "  " + cam.describe() + "\n";
  text += "  " + stereo.describe() +
          fmt::format(" (unmatched: {} {}, {} {})\n", unmatched[0], cameras[0].name, unmatched[1],
                      cameras[1].name);
  text += "  " + imu.describe() + "\n";
  text += groundtruth ? "  " + groundtruth->describe() + "\n" : std::string("  ground truth: none\n");
  if (gnss) {
    text += "  " + gnss->describe() + "\n";
    if (p_b_gnss) {
      text += fmt::format("  gnss0 antenna in the body frame: [{:.3f}, {:.3f}, {:.3f}] m\n", p_b_gnss->x(),
                          p_b_gnss->y(), p_b_gnss->z());
    }
  } else {
    text += "  gnss: none\n";
  }
  return text;
}

StatusOr<StereoMatch> match_stereo(const std::vector<ImageRecord>& left,
                                   const std::vector<ImageRecord>& right, DurationNs tolerance_ns) {
  if (tolerance_ns < 0) {
    return absl::InvalidArgumentError(fmt::format(
        "stereo tolerance {} ns is negative; use 0 for exact timestamps or a positive value", tolerance_ns));
  }
  for (const DurationNs period : {median_period(stamps(left)), median_period(stamps(right))}) {
    if (period > 0 && 2 * tolerance_ns >= period) {
      return absl::InvalidArgumentError(fmt::format(
          "stereo tolerance {} ns is not below half the camera period ({} ns): frames of different "
          "exposures could be paired; use a tolerance below {} ns",
          tolerance_ns, period, (period + 1) / 2));
    }
  }
  StereoMatch match;
  std::size_t i = 0;
  std::size_t j = 0;
  while (i < left.size() && j < right.size()) {
    const DurationNs dt = right[j].t_ns - left[i].t_ns;
    if (std::abs(dt) <= tolerance_ns) {
      match.frames.push_back(StereoFrame{left[i].t_ns, left[i], right[j]});
      ++i;
      ++j;
    } else if (dt > 0) {
      match.unmatched_left.push_back(left[i++].t_ns);
    } else {
      match.unmatched_right.push_back(right[j++].t_ns);
    }
  }
  for (; i < left.size(); ++i) match.unmatched_left.push_back(left[i].t_ns);
  for (; j < right.size(); ++j) match.unmatched_right.push_back(right[j].t_ns);
  return match;
}

StatusOr<cv::Mat> DatasetReader::load_image(int cam, const ImageRecord& record) const {
  if (cam != 0 && cam != 1) {
    return absl::InvalidArgumentError(
        fmt::format("camera index {} is out of range; use 0 (left) or 1 (right)", cam));
  }
  const auto& model = calibration().cameras[static_cast<std::size_t>(cam)].model;
  return io::load_image(record, model ? model->width() : 0, model ? model->height() : 0);
}

std::vector<std::string> dataset_formats() { return {"euroc"}; }

StatusOr<std::unique_ptr<DatasetReader>> open_dataset(const std::string& format,
                                                      const DatasetOptions& options) {
  if (format == "euroc") return open_euroc_dataset(options);
  std::string known;
  for (const std::string& f : dataset_formats()) known += (known.empty() ? "" : ", ") + f;
  return absl::InvalidArgumentError(
      fmt::format("unknown dataset format '{}'; known formats: {}", format, known));
}

}  // namespace mrvs::io
