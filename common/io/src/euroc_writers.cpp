// Writers of the EuRoC ASL CSV files (the readers are in euroc_dataset.cpp).
#include <iterator>

#include <fmt/format.h>

#include "mrvs/core/file.h"
#include "mrvs/io/dataset.h"
#include "write_rows.h"

namespace mrvs::io {
namespace {

// The real EuRoC headers.
constexpr const char* kImageHeader = "#timestamp [ns],filename";
constexpr const char* kImuHeader =
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
    "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]";

}  // namespace

Status write_euroc_image_csv(const std::filesystem::path& csv, const std::vector<ImageRecord>& records) {
  MRVS_RETURN_IF_ERROR(check_rows_to_write(csv, records, [](const ImageRecord& r) {
    return !r.path.filename().empty() && r.path.filename().string().find(',') == std::string::npos;
  }));
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kImageHeader);
  for (const ImageRecord& r : records) {
    fmt::format_to(std::back_inserter(out), "{},{}\n", r.t_ns, r.path.filename().string());
  }
  return write_file_atomically(csv, fmt::to_string(out));
}

Status write_euroc_imu_csv(const std::filesystem::path& csv, const std::vector<ImuSample>& samples) {
  MRVS_RETURN_IF_ERROR(check_rows_to_write(
      csv, samples, [](const ImuSample& s) { return s.gyro_radps.allFinite() && s.accel_mps2.allFinite(); }));
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kImuHeader);
  for (const ImuSample& s : samples) {
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{},{}\n", s.t_ns, s.gyro_radps.x(),
                   s.gyro_radps.y(), s.gyro_radps.z(), s.accel_mps2.x(), s.accel_mps2.y(), s.accel_mps2.z());
  }
  return write_file_atomically(csv, fmt::to_string(out));
}

}  // namespace mrvs::io
