#pragma once
// On-demand loading of dataset images as 8-bit grayscale.
#include <opencv2/core/mat.hpp>

#include "mrvs/core/status.h"
#include "mrvs/io/types.h"

namespace mrvs::io {

/// Reads `record.path` as an 8-bit single-channel image (CV_8UC1). Colour images are
/// converted to grayscale and 16-bit images scaled to 8 bits (value / 256).
/// When expected_width and expected_height are > 0 the size is checked (pixels).
/// Errors name the file: NotFound when it does not exist, InvalidArgument when it cannot
/// be decoded or has the wrong size. Never throws.
StatusOr<cv::Mat> load_image(const ImageRecord& record, int expected_width, int expected_height);

}  // namespace mrvs::io
