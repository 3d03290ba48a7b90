#include "mrvs/sim/map_options.h"

namespace mrvs::sim {

MapOptions indoor_map_options() { return MapOptions{}; }

MapOptions outdoor_map_options() {
  MapOptions options;
  options.spacing_near_m = 0.10;
  options.spacing_far_m = 0.25;
  options.near_distance_m = 15.0;
  options.tile_size_m = 1.0;
  options.far_above_z_m = 20.0;
  options.station_spacing_m = 10.0;
  options.station_height_m = 2.0;
  options.station_max_range_m = 80.0;
  return options;
}

MapOptions test_map_options() {
  MapOptions options;
  options.spacing_near_m = 0.03;
  options.spacing_far_m = 0.03;
  return options;
}

}  // namespace mrvs::sim
