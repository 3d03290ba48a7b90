#include "mrvs/sim/png_writer.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <system_error>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace mrvs::sim {

StatusOr<std::vector<std::uint8_t>> encode_png(const cv::Mat& image) {
  if (image.empty() || image.type() != CV_8UC1) {
    return absl::InvalidArgumentError(
        fmt::format("encode_png: expected a non-empty CV_8UC1 image, got {}x{} type {}", image.cols,
                    image.rows, image.type()));
  }
  std::vector<std::uint8_t> bytes;
  // No IMWRITE_PNG_COMPRESSION: OpenCV then uses its speed path (SUB filter, Z_BEST_SPEED);
  // RLE is named explicitly so the output does not depend on OpenCV's default strategy.
  const std::vector<int> params = {cv::IMWRITE_PNG_STRATEGY, cv::IMWRITE_PNG_STRATEGY_RLE};
  try {
    if (!cv::imencode(".png", image, bytes, params))
      return absl::InternalError("encode_png: cv::imencode failed");
  } catch (const cv::Exception& e) {
    return absl::InternalError(fmt::format("encode_png: {}", e.what()));
  }
  return bytes;
}

Status write_file(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) {
    return absl::UnavailableError(
        fmt::format("cannot open '{}' for writing: {}", path.string(), std::strerror(errno)));
  }
  const std::size_t written = bytes.empty() ? 0 : std::fwrite(bytes.data(), 1, bytes.size(), f);
  const int write_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (written != bytes.size() || !closed) {
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    return absl::UnavailableError(fmt::format("cannot write {} bytes to '{}': {}", bytes.size(),
                                              path.string(),
                                              std::strerror(write_errno != 0 ? write_errno : errno)));
  }
  return absl::OkStatus();
}

Status write_png(const std::filesystem::path& path, const cv::Mat& image) {
  StatusOr<std::vector<std::uint8_t>> bytes = encode_png(image);
  if (!bytes.ok()) {
    return absl::Status(bytes.status().code(), fmt::format("writing '{}': {}", path.string(),
                                                           std::string(bytes.status().message())));
  }
  return write_file(path, *bytes);
}

}  // namespace mrvs::sim
