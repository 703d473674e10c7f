#pragma once
// Shared pieces of the `proctex rgbn` subcommands (cli/cmd_rgbn*.cpp).
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "image/image.h"
#include "rgbn/rgbn.h"

namespace proctex::cli::rgbn_cli {

// Reads an RGBN EXR (channels R,G,B,N.X,N.Y,N.Z).
rgbn::Rgbn load_input(const std::string& path);
// Writes an RGBN EXR; when `preview` is not empty also a Lambert-shaded PNG/EXR of it.
void save_output(const rgbn::Rgbn& image, const std::string& path, const std::string& preview = {});
// Photos and their light directions from either `--lights FILE.json` ([{"image":..., "light":
// [x,y,z] or "az,el"}, ...]) or positional images with one --light each.
void load_lit_photos(const std::vector<std::string>& images, const std::vector<std::string>& lights,
                     const std::string& lights_file, std::vector<Image>& photos, std::vector<rgbn::Vec3>& dirs,
                     size_t min_photos);

void add_edit_commands(CLI::App& rgbn, GlobalOptions& global);     // stamp, pen, edit
void add_display_commands(CLI::App& rgbn, GlobalOptions& global);  // mip, ptm, stereo, synth

}  // namespace proctex::cli::rgbn_cli
