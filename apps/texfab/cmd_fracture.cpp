// SPDX-License-Identifier: GPL-3.0-or-later
// texfab fracture: break a model into Voronoi pieces whose new faces show the interior of the
// material (lazy solid synthesis, Dong et al. 2008), continuous with the outside.
#include "apps/texfab/break_command.h"
#include "apps/texfab/command.h"

#include <memory>

namespace texfab::cli {

Command addFractureCommand(CLI::App& root) {
  auto job = std::make_shared<BreakJob>();
  geometry::FractureOptions& o = job->options.fracture.emplace();
  Flags f(root.add_subcommand("fracture", "Break a model into Voronoi pieces: every piece is closed, and the new "
                                          "faces show the interior of the material (a solid texture)"));
  addBreakInput(f, *job);
  f.option("--pieces", o.pieces, "Pieces: Voronoi sites inside the model, drawn from --seed",
           {1, geometry::kMaxFracturePieces});
  f.numbers("--impact", 3, "X,Y,Z", "Concentrate the pieces around this point (model units), as a blow would", {},
            false, [job](const std::vector<double>& v) { job->options.fracture->impact = Eigen::Vector3d(v[0], v[1], v[2]); });
  f.option("--roughness", o.roughness,
           "Relief of the cracks, a fraction of the pieces' size; the two sides of a crack still fit exactly", {0, 0.25});
  f.option("--min-volume", o.minVolume, "Merge pieces smaller than this fraction of the model's volume into a neighbour",
           {0, 0.5});
  addBreakOptions(f, *job);
  return {f.app(), [job] { runBreak("fracture", *job); }};
}

} // namespace texfab::cli
