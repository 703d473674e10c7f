// proctex devices: the OpenCL devices this machine offers and which one proctex would use.
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/output.h"
#include "kernels/runtime.h"

namespace proctex::cli {

void add_devices_command(CLI::App& app, GlobalOptions& global) {
  auto* cmd = app.add_subcommand("devices", "List the OpenCL devices and show which one proctex uses");
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json, "Print the list as JSON");
  cmd->callback([json, &global] {
    const auto devices = ocl::list_devices();
    const auto chosen = ocl::choose_device(global.device);
    if (*json) {
      nlohmann::json out = nlohmann::json::array();
      for (const auto& d : devices)
        out.push_back({{"index", d.index}, {"name", d.name}, {"platform", d.platform}, {"vendor", d.vendor},
                       {"version", d.version}, {"driver", d.driver}, {"type", d.is_gpu ? "gpu" : "cpu"},
                       {"compute_units", d.compute_units}, {"global_memory_bytes", d.global_memory},
                       {"max_allocation_bytes", d.max_allocation}, {"selected", d.index == chosen.index}});
      print_json(out);
      return;
    }
    std::vector<std::vector<std::string>> rows = {{"", "#", "type", "units", "memory", "name", "platform"}};
    for (const auto& d : devices)
      rows.push_back({d.index == chosen.index ? "*" : "", std::to_string(d.index), d.is_gpu ? "gpu" : "cpu",
                      std::to_string(d.compute_units), fmt::format("{:.1f} GB", d.global_memory / 1e9), d.name,
                      d.platform});
    print_table(rows);
    std::printf("\n* = used (choose with --device INDEX|NAME or PROCTEX_DEVICE)\n");
  });
}

}  // namespace proctex::cli
