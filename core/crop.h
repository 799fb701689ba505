// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Cropping: a rectangle of an image, every channel, same format.

#include "core/image.h"

namespace texfab {

/// The width x height pixels of `image` from (x0, y0). Throws texfab::Error unless the rectangle
/// is non-empty and lies inside the image.
Image crop(const Image& image, int x0, int y0, int width, int height);

} // namespace texfab
