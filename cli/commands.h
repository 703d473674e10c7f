#pragma once
// Each proctex subcommand lives in its own cli/cmd_<name>.cpp and registers itself on the root
// CLI11 app through one of these functions. A command parses, calls a library, prints; it throws
// proctex::Error (exit 1) or proctex::UsageError (exit 2) and main() formats the message.
#include <CLI/CLI.hpp>
#include <string>

namespace proctex::cli {

// Options every command can see (set on the root app before the subcommand runs).
struct GlobalOptions {
  std::string device;  // --device / PROCTEX_DEVICE: index or substring of the device name
  bool quiet = false;  // --quiet: no progress on stderr
};

void add_devices_command(CLI::App& app, GlobalOptions& global);
void add_shaders_command(CLI::App& app, GlobalOptions& global);
void add_render_command(CLI::App& app, GlobalOptions& global);
void add_compare_command(CLI::App& app, GlobalOptions& global);
void add_catalog_command(CLI::App& app, GlobalOptions& global);
void add_match_command(CLI::App& app, GlobalOptions& global);
void add_morph_command(CLI::App& app, GlobalOptions& global);
void add_serve_command(CLI::App& app, GlobalOptions& global);
void add_rgbn_command(CLI::App& app, GlobalOptions& global);
void add_synth_command(CLI::App& app, GlobalOptions& global);
// `catalog link` (cmd_catalog_link.cpp): added to the `catalog` subcommand.
void add_catalog_link_command(CLI::App& catalog, GlobalOptions& global);

}  // namespace proctex::cli
