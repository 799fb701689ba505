// SPDX-License-Identifier: GPL-3.0-or-later
// texfab cut: cut a model by planes; every piece is closed, and the cut faces show the interior of
// the material (lazy solid synthesis, Dong et al. 2008).
#include "apps/texfab/break_command.h"
#include "apps/texfab/command.h"

#include <memory>

namespace texfab::cli {

Command addCutCommand(CLI::App& root) {
  auto job = std::make_shared<BreakJob>();
  Flags f(root.add_subcommand("cut", "Cut a model by planes: every piece is closed, and its cut faces show the "
                                     "interior of the material (a solid texture)"));
  addBreakInput(f, *job);
  f.app()
      ->add_option_function<std::vector<std::string>>(
          "--plane",
          [job](const std::vector<std::string>& planes) {
            for (const std::string& text : planes) {
              const std::vector<double> v = parseNumbers("--plane", text, 6);
              const geometry::CutPlane plane{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
              if (!(plane.normal.norm() > 0)) throw CLI::ValidationError("--plane", "the normal is zero in '" + text + "'");
              job->options.planes.push_back(plane);
            }
          },
          "A cutting plane: a point and a normal (model units; the normal need not be unit). Repeat for more "
          "planes: the pieces are the model within each cell of all the planes")
      ->type_name("PX,PY,PZ,NX,NY,NZ")
      ->allow_extra_args(false)
      ->required();
  addBreakOptions(f, *job);
  return {f.app(), [job] { runBreak("cut", *job); }};
}

} // namespace texfab::cli
