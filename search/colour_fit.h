#pragma once
// Colour fitting: a catalogue start usually has the right structure in the wrong colours (its
// colours were drawn at random), and the default metric punishes colour hard; the structural
// metrics see lightness, so a wrong colour also changes contrast and polarity. Most shaders mix
// their colour parameters linearly, per channel, by masks and shading:
//     image(x) = b(x) + sum_j w_j(x) * colour_j
// so K + 1 renders (all colours black; then each colour alone at a dark grey) give the basis b, w_j, and
// any choice of colours is a weighted sum of images - no further renders. One extra render at
// half the start's colours checks the linearity; a shader that is not linear in its colours is
// left alone (the refinement still searches its colours, only more slowly).
//
// The fit itself is closed-form histogram matching projected on the linear model: rank the
// model's pixels by lightness, give each pixel the target colour of the same rank, solve the
// per-channel least squares for the colours, repeat (ranks move). Each colour mask is tried as
// the initial ranking in both directions (dark-on-light and light-on-dark), and the result with
// the best colour similarity is kept. An optional NLopt polish then maximises the colour metric
// on the same basis.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "metrics/metric.h"
#include "shaders/renderer.h"

namespace proctex::search {

// What the colour fit compares with: the target at the fit's resolution, once.
struct ColourTarget {
  int resolution = 64;
  Image rgb;                          // centre square of the target, resolution^2, linear RGB
  // The fit's sort axes: luminance and, when its order differs from luminance's, the target's
  // principal colour axis (two materials of one lightness in different hues - a yellow joint
  // between lavender pavers - interleave in lightness order, and a fit by lightness ranks
  // averages them to grey).
  std::vector<std::array<float, 3>> axes;
  std::vector<std::vector<float>> sorted;  // its pixels sorted along each axis, RGB triples
  metrics::Features colour;           // its features under the "colour" metric
  const metrics::Metric* colour_metric = nullptr;
};
ColourTarget make_colour_target(const Image& target, int resolution = 64);

struct ColourFitResult {
  std::vector<float> packed;     // the start with fitted colours (unchanged when not fitted)
  bool fitted = false;           // false: no free colour, or the shader is not linear in them
  double before = 0.0;           // colour similarity at the start's colours
  double after = 0.0;            // ... at the fitted colours
  double linearity_error = 0.0;  // max |prediction - render| at half the start's colours
  Image preview;                 // the image at the fitted colours (the render when not fitted)
};

// Fits the free colours (searchable, not in `pinned`) of each start; all bases are rendered in
// one launch at the target's resolution (so `packed.size() * (K + 3)` renders). `polish` adds an
// NLopt pass on the colour metric (about a thousand cheap evaluations, no renders).
//
// `registered`: instead of matching histograms, register each start's render with the target
// (the best circular shift of metrics/aligned.h) and solve the colours by least squares on the
// pixels. For a shape that is already exact (the align stage of a deterministic pattern) the
// pixels give the colours exactly where the histogram fit is only close; for a texture (no pixel
// correspondence) it is meaningless. The result is kept whether or not the colour metric agrees.
std::vector<ColourFitResult> fit_colours(const ShaderDecl& decl, const std::vector<std::vector<float>>& packed,
                                         const std::vector<uint32_t>& seeds, const std::vector<std::string>& pinned,
                                         const ColourTarget& target, Renderer& renderer, bool polish,
                                         bool registered = false);

// The free colours of `packed` (its shape kept) that reproduce `wanted` (side x side linear RGB,
// 3 floats per pixel) pixel for pixel where `mask` (one byte per pixel) is non-zero: least
// squares on the shader's colour basis (free colours + 1 renders, no histogram, no registration).
// `mse`: the model's mean squared RGB residual on the mask - exact for a shader linear in its
// colours (check that with fit_colours' linearity test first). The pixel polish's inner step.
// `bounds`: Clamped - the least-squares colours, each clamped into its range (`mse` theirs);
// Unconstrained - `mse` is that of the unconstrained least-squares colours (smooth in the shape),
// `packed` holds them clamped; Bounded - the least squares solved inside the colours' ranges (per
// channel, every set of colours at a bound tried: the best colours a render can have, and `mse`
// theirs; continuous in the shape). The pixel polish's objective was Unconstrained (session 9: a
// clamped colour made the objective kink where the search stalled); with a colour out of range that
// objective reports an image no render gives - a soft ring whose colour wanted blue 1.2 stopped at
// RMS 1e-5 by the model and 0.0033 rendered (session 14) - so it is Bounded since.
// `zero_offset`: the caller knows the render with every free colour black is black (a shader
// that mixes its colours, as a two-colour pattern does: `offset_black` of an earlier fit of the
// same shader said so), and that render is skipped - a third of a two-colour fit's renders.
enum class ColourBounds { Clamped, Unconstrained, Bounded };
struct PixelColourFit {
  std::vector<float> packed;
  double mse = 1.0;
  long renders = 0;
  bool offset_black = false;  // the render with every free colour black was black
};
PixelColourFit fit_colours_to_pixels(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                                     const std::vector<std::string>& pinned, const std::vector<float>& wanted,
                                     const std::vector<uint8_t>& mask, int side, Renderer& renderer,
                                     ColourBounds bounds = ColourBounds::Clamped, bool zero_offset = false);

// Renders fit_colours spends for `starts` starting points of `decl`.
long colour_fit_renders(const ShaderDecl& decl, const std::vector<std::string>& pinned, size_t starts);

}  // namespace proctex::search
