// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The exemplar graph file (docs/exemplar-graphs.md#the-file):
//
//   {
//     "exemplars": [ {"name": "regions", "image": "regions.png", "maps": {"height": "regions-h.png"}},
//                    {"name": "grain", "image": "grain.png", "maps": {"height": "grain-h.png"}} ],
//     "root": "regions",
//     "edges": [ {"from": "regions", "to": "grain", "scale": 16, "region": "grain-mask.png"} ],
//     "colors": "coarse"
//   }
//
// Images are read relative to the file's folder. "root" is optional (default: the first
// exemplar). An edge's "scale" is how many pixels of `to` one pixel of `from` spans: a power of two
// from 2 up; from == to makes an exemplar self-similar (an infinite zoom). Its optional "region"
// limits it to part of `from`: [x, y, width, height] in pixels (wrapping), or a mask image of the
// source exemplar's size whose first channel is at least 0.5 inside. An exemplar's optional "maps"
// are its companion maps ("normal", "roughness", "height"), each given for every exemplar or for
// none, of its size. Exemplars are square with power-of-two sides; sides may differ (withOneSide
// magnifies the smaller ones), as long as an exemplar of another size that details one spans at
// most half of it.
// "colors" (optional): "coarse" (default), finer exemplars take on the colours of the coarser ones
// they detail (ExemplarGraph::coarseColors); "own", each exemplar shows its own.

#include "synthesis/exemplar_graph.h"

#include <filesystem>

namespace texfab::synthesis {

/// Reads and validates a graph file (ExemplarGraph::validate), the root first. Throws texfab::Error
/// with one line naming the file and the problem: not JSON, an unknown or missing field, an
/// unknown or repeated name, a scale that is not a power of two above 1, an unreadable image. Its
/// exemplars are brought to one side (withOneSide).
ExemplarGraph readExemplarGraph(const std::filesystem::path& path);

/// The file's "colors" value that gives `graph`'s ExemplarGraph::coarseColors: "coarse" or "own".
inline const char* graphColorsName(const ExemplarGraph& graph) { return graph.coarseColors ? "coarse" : "own"; }

} // namespace texfab::synthesis
