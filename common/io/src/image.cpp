#include "mrvs/io/image.h"

#include <string>
#include <system_error>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace mrvs::io {
namespace {

/// Brings a decoded image to CV_8UC1 (imread with IMREAD_GRAYSCALE normally does this).
StatusOr<cv::Mat> to_gray8(const cv::Mat& image, const ImageRecord& record) {
  if (image.type() == CV_8UC1) return image;
  if (image.channels() != 1) {
    return absl::InvalidArgumentError(
        fmt::format("image {} (t = {} ns) decoded with {} channels; expected a grayscale image; convert it "
                    "to 8-bit grayscale PNG",
                    record.path.string(), record.t_ns, image.channels()));
  }
  cv::Mat gray;
  if (image.depth() == CV_16U) {
    image.convertTo(gray, CV_8U, 1.0 / 256.0);
  } else if (image.depth() == CV_8S || image.depth() == CV_16S) {
    image.convertTo(gray, CV_8U, 1.0, 128.0);
  } else {
    // Floating point images are taken to hold intensities in [0, 1].
    image.convertTo(gray, CV_8U, 255.0);
  }
  return gray;
}

}  // namespace

StatusOr<cv::Mat> load_image(const ImageRecord& record, int expected_width, int expected_height) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(record.path, ec)) {
    return absl::NotFoundError(fmt::format(
        "image {} (t = {} ns) does not exist; re-extract the dataset or remove its row from the camera's "
        "data.csv",
        record.path.string(), record.t_ns));
  }
  cv::Mat image;
  try {
    image = cv::imread(record.path.string(), cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception& e) {
    return absl::InvalidArgumentError(fmt::format("cannot decode image {} (t = {} ns): {}; replace the file",
                                                  record.path.string(), record.t_ns, e.what()));
  }
  if (image.empty()) {
    return absl::InvalidArgumentError(
        fmt::format("cannot decode image {} (t = {} ns): not a readable image (corrupt, empty or an "
                    "unsupported format); replace the file",
                    record.path.string(), record.t_ns));
  }
  MRVS_ASSIGN_OR_RETURN(cv::Mat gray, to_gray8(image, record));
  if (expected_width > 0 && expected_height > 0 &&
      (gray.cols != expected_width || gray.rows != expected_height)) {
    return absl::InvalidArgumentError(fmt::format(
        "image {} (t = {} ns) is {}x{} pixels but the camera calibration says {}x{}; use the "
        "calibration that belongs to this dataset, or the images it was made for",
        record.path.string(), record.t_ns, gray.cols, gray.rows, expected_width, expected_height));
  }
  return gray;
}

}  // namespace mrvs::io
