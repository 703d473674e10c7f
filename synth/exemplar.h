#pragma once
// An exemplar: the small image synthesis copies from, plus any maps that must stay aligned with it
// (normal, height, roughness). Every map is carried through the same coordinate map; the maps also
// take part in the matching (weighted), so a feature present only in a map is kept too.
#include <filesystem>
#include <string>
#include <vector>

#include "image/image.h"

namespace proctex::synth {

inline constexpr int kMinExemplarSide = 16;   // smaller: no texture left to copy
inline constexpr int kMaxExemplarSide = 512;  // larger: analysis memory (levels x texels) explodes

enum class MapKind {
  Colour,  // RGB (sRGB-encoded for matching)
  Normal,  // tangent-space normal stored as (n + 1) / 2; compared on components, renormalised
  Grey,    // one channel (height, roughness, ...): the mean of R, G, B
};

struct ExemplarMap {
  std::string name;   // the file name, for messages
  MapKind kind = MapKind::Colour;
  Image image;        // as loaded (linear RGB float)
};

struct Exemplar {
  std::string name;
  Image colour;                    // linear RGB
  std::vector<ExemplarMap> maps;   // same size as colour
  float map_weight = 0.5f;         // weight of every map channel relative to a colour channel

  int width() const { return colour.width; }
  int height() const { return colour.height; }
};

// Checks size limits, finite pixels and that every map has the colour's size. Throws
// proctex::Error naming the offending file.
void validate(const Exemplar& exemplar);

// Loads an exemplar image with the checks above (unreadable file, < 16 px, > 512 px, NaN/inf).
Image load_exemplar_image(const std::filesystem::path& path);

// "normal", "height", "grey", "colour" ... -> MapKind; guesses from a file name when `kind` is
// empty ("*normal*" -> Normal, "*height*|*rough*|*disp*|*spec*|*ao*" -> Grey, else Colour).
MapKind parse_map_kind(const std::string& kind, const std::string& file_name);

// The matching channels of an exemplar, planar: channel c of texel (x, y) is
// data[c * w * h + y * w + x]. Colour is sRGB-encoded, normals in [-1, 1] scaled by the map
// weight, grey maps sRGB-encoded and scaled by the map weight. `normal_groups` lists the first
// channel of every 3-channel normal (renormalised after filtering).
struct Channels {
  int width = 0, height = 0, count = 0;
  std::vector<float> data;
  std::vector<int> normal_groups;
  std::vector<float> normal_scale;  // the weight a normal group was scaled by
};
Channels matching_channels(const Exemplar& exemplar);

}  // namespace proctex::synth
