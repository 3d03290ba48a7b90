#pragma once
// Tuning of the stereo image renderer (simulator.md section 4.3 and the photometric knobs
// of section 7). Defaults: adaptive anti-aliasing, no noise, no vignetting, equal camera
// gains, fixed exposure, no motion blur, uniform light.
#include "mrvs/config/options.h"

namespace mrvs::sim {

/// Anti-aliasing scheme.
enum class AntiAliasing {
  kAdaptive,  ///< 1 ray per pixel with trilinear mip filtering, then 2x2 level-0 subsamples
              ///< on pixels next to a face change (4-neighbourhood)
  kFull,      ///< 2x2 level-0 subsamples on every pixel (4x the cost)
  kNone,      ///< 1 ray per pixel, level-0 texture (point sampling: aliases)
};

struct RenderOptions : config::OptionsEquality<RenderOptions> {
  AntiAliasing aa = AntiAliasing::kAdaptive;  ///< anti-aliasing scheme
  double max_distance_m = 300.0;              ///< rays hitting nothing closer see the sky, m
  double min_cos_incidence = 0.2;             ///< floor of |n . d| in the mip footprint
  double stereo_gain_mismatch = 0.0;          ///< cam1 gain = 1 + this (cam0 gain is 1)
  double vignetting = 0.0;                    ///< eps_vig at the farthest image corner (e.g. -0.3)
  double read_noise_sigma = 0.0;              ///< Gaussian read noise, DN
  bool shot_noise = false;                    ///< add shot noise of variance DN / K
  double shot_noise_k = 4.0;                  ///< K, DN per photo-electron
  bool exposure_walk = false;                 ///< per-frame log-gain random walk (exposure_gains)
  double exposure_sigma = 0.02;               ///< log-gain step per frame
  double exposure_limit = 0.3;                ///< gain stays within 1 -+ this
  bool motion_blur = false;          ///< integrate each image over its exposure along the true motion
  double exposure_ms = 5.0;          ///< exposure (global shutter), centred on the frame's time, ms
  double blur_step_px = 1.0;         ///< the exposure's sub-samples move the image at most this far apart, px
  int blur_max_samples = 32;         ///< at most this many sub-samples per image
  bool auto_exposure = false;        ///< per-frame exposure from the previous image's mean (AutoExposure)
  double ae_target_dn = 110.0;       ///< mean DN the auto-exposure aims at
  double ae_deadband_ev = 0.1;       ///< no change while |log2(target / mean)| is below this
  double ae_damping = 0.5;           ///< fraction of the error (in EV) corrected per frame
  double ae_step_ev = 0.125;         ///< the exposure moves in steps of this many EV
  double ae_min_exposure_ms = 0.05;  ///< shortest exposure, ms
  double ae_max_exposure_ms = 20.0;  ///< longest exposure, ms (and never past the frame interval)
  double ae_max_analog_gain = 4.0;   ///< analog gain once the exposure is at its longest (scales noise)
  bool dim_area = false;             ///< a dim part of the scene (Illumination)
  double dim_level = 0.15;           ///< light at the dim area's centre (1 elsewhere)
  double dim_radius_m = 3.0;         ///< Gaussian radius of the dim area (horizontal), m

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("aa", aa,
      enum_names<AntiAliasing>({{"adaptive", AntiAliasing::kAdaptive},
                                {"full", AntiAliasing::kFull},
                                {"none", AntiAliasing::kNone}}),
      "anti-aliasing: adaptive | full | none");
    v("max_distance_m", max_distance_m, in_range(0.01, 1.0e5), "sky beyond this ray length, m");
    v("min_cos_incidence", min_cos_incidence, in_range(0.01, 1.0), "floor of |n.d| in the mip footprint");
    v("stereo_gain_mismatch", stereo_gain_mismatch, in_range(-0.5, 0.5), "cam1 gain = 1 + this");
    v("vignetting", vignetting, in_range(-1.0, 1.0), "albedo offset at the farthest corner, * (r/r_max)^2");
    v("read_noise_sigma", read_noise_sigma, in_range(0.0, 64.0), "Gaussian read noise, DN");
    v("shot_noise", shot_noise, any(), "shot noise of variance DN / K");
    v("shot_noise_k", shot_noise_k, in_range(0.01, 1000.0), "K, DN per photo-electron");
    v("exposure_walk", exposure_walk, any(), "per-frame log-gain random walk shared by both cameras");
    v("exposure_sigma", exposure_sigma, in_range(0.0, 1.0), "log-gain step per frame");
    v("exposure_limit", exposure_limit, in_range(0.0, 0.9), "gain stays within 1 -+ this");
    v("motion_blur", motion_blur, any(), "integrate each image over its exposure along the true motion");
    v("exposure_ms", exposure_ms, in_range(0.01, 50.0), "exposure, centred on the frame's time, ms");
    v("blur_step_px", blur_step_px, in_range(0.05, 10.0), "image motion between two sub-samples at most, px");
    v("blur_max_samples", blur_max_samples, in_range(1, 256), "sub-samples per image at most");
    v("auto_exposure", auto_exposure, any(), "per-frame exposure from the previous image's mean DN");
    v("ae_target_dn", ae_target_dn, in_range(1.0, 254.0), "mean DN the auto-exposure aims at");
    v("ae_deadband_ev", ae_deadband_ev, in_range(0.0, 2.0),
      "no change while |log2(target/mean)| is below, EV");
    v("ae_damping", ae_damping, in_range(0.01, 1.0), "fraction of the error corrected per frame");
    v("ae_step_ev", ae_step_ev, in_range(0.0, 1.0), "exposure steps, EV (0: continuous)");
    v("ae_min_exposure_ms", ae_min_exposure_ms, in_range(0.001, 100.0), "shortest exposure, ms");
    v("ae_max_exposure_ms", ae_max_exposure_ms, in_range(0.001, 1000.0),
      "longest exposure, ms (capped by the frame interval)");
    v("ae_max_analog_gain", ae_max_analog_gain, in_range(1.0, 64.0), "analog gain at the longest exposure");
    v("dim_area", dim_area, any(), "a dim part of the scene that forces long exposures");
    v("dim_level", dim_level, in_range(0.01, 1.0), "light at the dim area's centre");
    v("dim_radius_m", dim_radius_m, in_range(0.1, 1000.0), "Gaussian radius of the dim area, m");
  }
};

}  // namespace mrvs::sim
