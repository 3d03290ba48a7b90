#pragma once
// The truth of each frame's exposure (sim0/exposure.csv) and of the scene's light
// (sim0/illumination.yaml): what the auto-exposure chose, the DN scale it gave, the image's
// mean and how many sub-samples the motion blur took.
#include <filesystem>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/sim/stereo_renderer.h"

namespace mrvs::sim {

struct FrameExposure {
  TimestampNs t_ns = 0;      ///< the frame's stamp (camera clock)
  double exposure_ms = 5.0;  ///< shutter open, centred on the frame's true time
  double analog_gain = 1.0;  ///< A_k
  double gain = 1.0;         ///< g_k: DN scale relative to render.exposure_ms at gain 1 (walk included)
  double mean_dn = 0.0;      ///< mean DN of the cam0 image
  int samples = 1;           ///< motion-blur sub-samples
};

/// "#timestamp [ns],exposure [ms],analog_gain,gain,mean_dn,blur_samples" and one row per frame.
Status write_exposure_csv(const std::filesystem::path& path, const std::vector<FrameExposure>& frames);
/// Reads it back; errors name the file, line and field.
StatusOr<std::vector<FrameExposure>> read_exposure_csv(const std::filesystem::path& path);

/// enabled, centre_xy, level, radius_m.
Status write_illumination_yaml(const std::filesystem::path& path, const Illumination& light);
StatusOr<Illumination> read_illumination_yaml(const std::filesystem::path& path);

}  // namespace mrvs::sim
