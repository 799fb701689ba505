// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Quality measures of broken models (break_model.h), as the tests and `--report` use them:
//  - crack match: the two faces of a crack show the same colour at the same 3-D points (each side
//    looked up through its own UVs and texture), against two unrelated points of the cut faces;
//  - crack-edge seams: where an outer face meets a cut face, the colour difference across the
//    edge against the difference at the same distance within a face (DESIGN.md's seam measure;
//    near 1: the edge shows no seam, as when the outside is the same solid texture).
// Colours are bilinear lookups of the base colour textures; deterministic (hashed sample points).

#include "render/break/break_model.h"

#include <cstddef>

namespace texfab::render {

struct CrackMatch {
  double difference = 0;           ///< mean absolute colour difference, same point seen from both sides
  double unrelatedDifference = 0;  ///< the same between unrelated points of the cut faces
  size_t samples = 0;
};

struct CrackSeams {
  double ratio = 0;                ///< across / within
  double acrossDifference = 0;     ///< outer face vs cut face, `distance` on either side of a crack edge
  double withinDifference = 0;     ///< two points of one face as far apart, beside the edge
  size_t samples = 0;
};

/// Up to `samples` points on the cut faces; the other side is the nearest cut face of another
/// piece within 1e-5 of the model's diagonal.
CrackMatch measureCrackMatch(const BrokenModel& model, size_t samples = 2000);

/// Points along the edges between outer and cut faces, `distance` (model units) away from the
/// edge on each side; 0 = 1.5 times the coarser of the two textures' texels.
CrackSeams measureCrackSeams(const BrokenModel& model, double distance = 0, size_t samples = 4000);

} // namespace texfab::render
