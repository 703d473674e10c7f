// proctex: the single command-line binary. Each subcommand lives in cli/cmd_<name>.cpp.
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

#include "cli/commands.h"
#include "core/error.h"
#include "core/version.h"
#include "kernels/runtime.h"

namespace {

void print_error(const proctex::Error& e) {
  std::string line = "proctex: error: " + e.message();
  if (!e.hint().empty()) line += " (" + e.hint() + ")";
  std::fprintf(stderr, "%s\n", line.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  using namespace proctex;
  CLI::App app{"proctex - turns photos into procedural textures: finds the OpenCL shader and "
               "parameters that reproduce a photo, renders them at any size, and morphs between textures.",
               "proctex"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("proctex ") + kVersion);
  cli::GlobalOptions global;
  app.add_option("--device", global.device,
                 "OpenCL device: index or part of a name from 'proctex devices' (default: $PROCTEX_DEVICE, "
                 "else the first GPU, else the CPU)");
  app.add_flag("-q,--quiet", global.quiet, "No progress output on stderr");
  app.failure_message([](const CLI::App* failed, const CLI::Error& e) {
    // Name the deepest subcommand the user typed, so the hint points at the right --help.
    std::string cmd = failed->get_name();
    for (const CLI::App* app = failed; !app->get_subcommands().empty();) {
      app = app->get_subcommands().front();
      cmd += " " + app->get_name();
    }
    return "proctex: error: " + std::string(e.what()) + " (run '" + cmd + " --help')\n";
  });

  cli::add_devices_command(app, global);
  cli::add_shaders_command(app, global);
  cli::add_render_command(app, global);
  cli::add_synth_command(app, global);
#ifdef PROCTEX_HAVE_METRICS
  cli::add_compare_command(app, global);
#endif
#ifdef PROCTEX_HAVE_CATALOG
  cli::add_catalog_command(app, global);
  cli::add_match_command(app, global);
  cli::add_catalog_link_command(*app.get_subcommand("catalog"), global);
  cli::add_morph_command(app, global);
#endif
#ifdef PROCTEX_HAVE_SERVER
  cli::add_serve_command(app, global);
#endif
#ifdef PROCTEX_HAVE_RGBN
  cli::add_rgbn_command(app, global);
#endif

  app.parse_complete_callback([&] {
    if (!global.device.empty()) ocl::Runtime::configure(global.device);
  });

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const UsageError& e) {
    print_error(e);
    return 2;
  } catch (const Error& e) {
    print_error(e);
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "proctex: error: out of memory (use a smaller --size or batch)\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "proctex: error: %s (this is a bug; please report it)\n", e.what());
    return 1;
  }
  return 0;
}
