// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Box-filtered downsampling of an image by an integer factor: each output pixel is the mean of a
// factor x factor block of input pixels (every channel, in the image's own values: no colour-space
// conversion). Trailing rows and columns that do not fill a block are dropped.

#include "core/image.h"

namespace texfab {

/// The image `factor` times smaller per side (at least 1x1), same channels and format.
/// Throws texfab::Error when factor < 1.
Image downsample(const Image& image, int factor);

} // namespace texfab
