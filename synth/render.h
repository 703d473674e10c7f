#pragma once
// Turning exemplar coordinates into files, window by window with bounded memory: the output is
// produced in strips of rows (each strip one synthesise() call, exact by spatial determinism) and
// streamed to every output file (colour, coordinate map, carried maps). Files are written to a
// temporary beside the target and renamed only when every file is complete.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "synth/exemplar.h"
#include "synth/synthesis.h"

namespace proctex::synth {

struct RenderOutputs {
  std::filesystem::path colour;                      // required
  std::filesystem::path coords;                      // optional: .exr, R = exemplar x, G = exemplar y
  std::vector<std::filesystem::path> maps;           // optional: one per exemplar.maps entry (or empty)
  int bits = 0;                                      // PNG/TIFF bit depth: 8 or 16; 0 = PNG 8, TIFF 16
  // PNG deflate level 0-9. 1 (the default) writes with the "sub" row filter only: on the bench's
  // 512^2 outputs 33-40% faster than libpng's adaptive choice of all five filters at the same
  // level, and the files 2-6% smaller. Any other level uses libpng's adaptive filters (9 = smallest).
  int png_compression = 1;
  // Seam blending of the written colour and maps (the coordinates stay exact): pixel p is the
  // weighted mean over its neighbours d (|dx|, |dy| <= blend_radius) of E[S(p + d) - d], the texel
  // neighbour d predicts for p, with tent weights (R + 1 - |dx|)(R + 1 - |dy|) (a prediction outside a
  // bounded exemplar is skipped): across a join the colour ramps from one patch to the other over
  // 2R pixels. Inside a patch every prediction is the same texel, so the output is an exact copy;
  // normals are averaged as vectors and renormalised. Off = each pixel copies one texel.
  bool blend_seams = false;
  int blend_radius = 3;
};

struct RenderStats {
  double seconds = 0;   // synthesis + writing
  int strips = 0;
  size_t peak_strip_pixels = 0;
};

// Checks extensions, bit depth and that the parent folders exist, before any work.
void check_outputs(const RenderOutputs& outputs, const Exemplar& exemplar);

// Synthesises `window` and writes the outputs. `max_strip_pixels` bounds the memory of one strip.
RenderStats render(Synthesizer& synth, const Exemplar& exemplar, const Window& window, const SynthOptions& options,
                   const RenderOutputs& outputs, const std::function<void(double)>& progress = {},
                   size_t max_strip_pixels = size_t(1) << 22);

// Writes images produced strip by strip (used by the graph synthesis): `produce(y0, rows, data)` fills
// one buffer per file with 3 floats per pixel: sRGB-encoded colour in [0, 1] for a colour file
// (converted to linear for EXR), raw values for a `raw` file (a coordinate map, written as float).
// Files go to temporaries renamed when all are complete, like render().
struct StripTarget {
  std::filesystem::path path;
  bool raw = false;
};
RenderStats write_strips(const std::vector<StripTarget>& files, int width, int height, int bits, int rows_per_strip,
                         const std::function<void(int y0, int rows, std::vector<std::vector<float>>& data)>& produce,
                         const std::function<void(double)>& progress = {});

// The colour of a coordinate map (linear RGB), for tests and small outputs.
Image colours_of(const std::vector<int32_t>& coords, int width, int height, const Image& source);

}  // namespace proctex::synth
