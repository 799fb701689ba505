// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What `texfab cut` and `texfab fracture` share: the flags of the model, its textures and the
// output, and the run (render/break_model.h): load, analyses, the job, one glTF node per piece,
// --separate, --preview and the report. Each command adds its geometry flags.

#include "apps/texfab/analysis.h"
#include "apps/texfab/cli.h"
#include "render/break/break_model.h"
#include "render/preview_renderer.h"
#include "synthesis/synthesize_solid.h"

#include <string>

namespace texfab::cli {

struct BreakJob {
  std::string model, output, exemplar, interior, separate, preview;
  render::BreakModelOptions options;
  uint32_t seed = 1;
  /// The solid textures' (outside in --mode solid, and the cut faces).
  SolidMethodChoice solid;
  float contrastGain = synthesis::SolidSynthesisOptions{}.contrastGain;
  int refinePasses = synthesis::SolidSynthesisOptions{}.refinePasses;
  double explode = 0;
  geometry::MeshWriteOptions write;
  render::RenderOptions previewOptions;
  UpChoice up;
  WrapChoice wrap = WrapChoice::Auto;
  CommonFlags common;
};

/// The model and -o (a command adds its geometry flags after them).
void addBreakInput(Flags& f, BreakJob& job);
/// The other shared flags: the textures (--exemplar, --mode, --interior, ...), the output
/// (--explode, --separate, --preview) and the common flags.
void addBreakOptions(Flags& f, BreakJob& job);

/// Runs the job with the geometry of job.options (planes or fracture).
void runBreak(const std::string& command, BreakJob& job);

} // namespace texfab::cli
