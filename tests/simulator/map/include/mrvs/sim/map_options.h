#pragma once
// Tuning of the synthetic "survey LiDAR" prior map (simulator.md section 5): sampling
// density, survey stations, position and intensity noise, global misalignment, holes.
#include <cstdint>

#include "mrvs/config/options.h"

namespace mrvs::sim {

/// How the map intensity I is derived from the scene albedo a (before noise and clipping).
enum class IntensityModel {
  kAlbedo,       ///< I = a
  kAlbedoCos,    ///< I = a * cos(incidence)^0.5, incidence at the station that scanned the point
  kAffineGamma,  ///< I = intensity_gain * a^intensity_gamma + intensity_offset
};

/// What a map hole removes.
enum class HoleMode {
  kTiles,  ///< whole sampling tiles (tile_size_m squares)
  kFaces,  ///< whole faces
};

/// How the map's points are made.
enum class MapModel {
  kSurface,  ///< spacing by distance to the trajectory, noise along the face (spacing_*, noise_*)
  kScanner,  ///< spacing, dropout and range noise of laser scanners at the stations (scan_*, range_*)
};

/// Prior-map options. Defaults: the indoor "Vicon room" survey of simulator.md section 5.
struct MapOptions : config::OptionsEquality<MapOptions> {
  MapModel model = MapModel::kSurface;    ///< surface sampling or scanner rays
  double scan_step_mrad = 0.75;           ///< scanner: angular step of the scan lattice, mrad
  double scan_min_spacing_m = 0.004;      ///< scanner: the merged scans are thinned to no closer, m
  double scan_min_elevation_deg = -60.0;  ///< scanner: nothing below this (the tripod), deg
  double range_noise_m = 0.0008;          ///< scanner: range noise sigma = this + range_noise_per_m * r, m
  double range_noise_per_m = 0.0003;      ///< scanner: growth of the range noise with range, m / m
  double dropout_start_deg = 60.0;        ///< scanner: returns start to drop beyond this incidence, deg
  double dropout_full_deg = 85.0;         ///< scanner: no return beyond this incidence, deg
  double spacing_near_m = 0.01;           ///< sample spacing on tiles within near_distance_m, metres
  double spacing_far_m = 0.02;            ///< largest spacing (far tiles), metres
  double near_distance_m = 2.5;           ///< s = clamp(spacing_near * d / near_distance, near, far), metres
  double tile_size_m = 0.5;              ///< side of a sampling tile (spacing and holes are per tile), metres
  double far_above_z_m = 0.0;            ///< tiles whose centre is higher get spacing_far (0 = off), metres
  double noise_normal_sigma_m = 0.003;   ///< position noise along the face normal, metres
  double noise_tangent_sigma_m = 0.001;  ///< position noise along each face axis, metres
  double intensity_noise_sigma = 0.01;   ///< additive intensity noise (intensity in [0, 1])
  IntensityModel intensity_model = IntensityModel::kAlbedo;  ///< albedo -> intensity
  double intensity_gain = 1.0;                               ///< a of the affine_gamma model
  double intensity_gamma = 1.0;                              ///< gamma of the affine_gamma model
  double intensity_offset = 0.0;                             ///< b of the affine_gamma model
  int num_stations = 4;              ///< scanner stations spread along the trajectory (station_spacing_m = 0)
  double station_spacing_m = 0.0;    ///< > 0: one station per this much path length instead, metres
  double station_height_m = 1.5;     ///< station height above the ground plane z = 0, metres
  double station_max_range_m = 0.0;  ///< stations see no farther than this (0 = unlimited), metres
  double misalignment_deg = 0.0;     ///< rotation of T_map_world about a random axis, degrees
  double misalignment_m = 0.0;       ///< translation of T_map_world in a random direction, metres
  double holes_fraction = 0.0;       ///< share of the visible surface area removed, [0, 1]
  HoleMode holes_mode = HoleMode::kTiles;  ///< unit removed by holes
  bool ply_ascii = false;                  ///< write data.ply as ASCII (debugging) instead of binary

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("model", model,
      enum_names<MapModel>({{"surface", MapModel::kSurface}, {"scanner", MapModel::kScanner}}),
      "surface (spacing by distance to the path) | scanner (laser scanners at the stations)");
    v("scan_step_mrad", scan_step_mrad, in_range(0.01, 100.0), "scanner angular step, mrad");
    v("scan_min_spacing_m", scan_min_spacing_m, in_range(0.0005, 1.0), "scanner: thinned to no closer, m");
    v("scan_min_elevation_deg", scan_min_elevation_deg, in_range(-90.0, 0.0),
      "scanner: lowest elevation, deg");
    v("range_noise_m", range_noise_m, in_range(0.0, 1.0), "scanner range noise at 0 m, m");
    v("range_noise_per_m", range_noise_per_m, in_range(0.0, 0.1), "scanner range noise growth, m per m");
    v("dropout_start_deg", dropout_start_deg, in_range(0.0, 90.0),
      "scanner: returns drop beyond this incidence");
    v("dropout_full_deg", dropout_full_deg, in_range(0.0, 90.0), "scanner: no return beyond this incidence");
    v("spacing_near_m", spacing_near_m, in_range(0.001, 10.0), "sample spacing near the trajectory, m");
    v("spacing_far_m", spacing_far_m, in_range(0.001, 10.0), "largest sample spacing, m (>= spacing_near_m)");
    v("near_distance_m", near_distance_m, at_least(0.0), "distance up to which spacing_near_m holds, m");
    v("tile_size_m", tile_size_m, in_range(0.01, 100.0), "sampling tile side, m");
    v("far_above_z_m", far_above_z_m, at_least(0.0),
      "tiles above this height use spacing_far_m (0 = off), m");
    v("noise_normal_sigma_m", noise_normal_sigma_m, in_range(0.0, 1.0), "position noise along the normal, m");
    v("noise_tangent_sigma_m", noise_tangent_sigma_m, in_range(0.0, 1.0), "position noise per face axis, m");
    v("intensity_noise_sigma", intensity_noise_sigma, in_range(0.0, 1.0), "intensity noise (I in [0, 1])");
    v("intensity_model", intensity_model,
      enum_names<IntensityModel>({{"albedo", IntensityModel::kAlbedo},
                                  {"albedo_cos", IntensityModel::kAlbedoCos},
                                  {"affine_gamma", IntensityModel::kAffineGamma}}),
      "albedo | albedo_cos (albedo*cos(incidence)^0.5) | affine_gamma (gain*albedo^gamma+offset)");
    v("intensity_gain", intensity_gain, in_range(-10.0, 10.0), "affine_gamma gain");
    v("intensity_gamma", intensity_gamma, in_range(0.01, 100.0), "affine_gamma exponent");
    v("intensity_offset", intensity_offset, in_range(-10.0, 10.0), "affine_gamma offset");
    v("num_stations", num_stations, in_range(1, 100000), "survey stations along the trajectory");
    v("station_spacing_m", station_spacing_m, at_least(0.0), "> 0: one station per this path length, m");
    v("station_height_m", station_height_m, in_range(0.0, 1000.0), "station height above z = 0, m");
    v("station_max_range_m", station_max_range_m, at_least(0.0), "station range (0 = unlimited), m");
    v("misalignment_deg", misalignment_deg, in_range(0.0, 180.0), "map rotation about a random axis, deg");
    v("misalignment_m", misalignment_m, at_least(0.0), "map translation in a random direction, m");
    v("holes_fraction", holes_fraction, in_range(0.0, 1.0), "share of the visible area removed");
    v("holes_mode", holes_mode,
      enum_names<HoleMode>({{"tiles", HoleMode::kTiles}, {"faces", HoleMode::kFaces}}), "tiles | faces");
    v("ply_ascii", ply_ascii, any(), "ASCII PLY instead of binary little-endian");
  }
};

/// Indoor survey (the defaults): 1 cm within 2.5 m of the trajectory, 2 cm beyond,
/// 4 stations at 1.5 m, 3 mm / 1 mm position noise.
MapOptions indoor_map_options();

/// Outdoor street canyon: 10 cm within 15 m of the route growing to 25 cm, facades above
/// 20 m at 25 cm, one station per 10 m of route at 2 m height, 80 m scanner range (150 m
/// costs 2-3x the time for 0.14 % more area on the 330 m test route).
MapOptions outdoor_map_options();

/// Unit-test preset: the indoor survey at 3 cm everywhere (about 380 k points indoors).
MapOptions test_map_options();

}  // namespace mrvs::sim
