// tetcut serve: the live session in a browser (see include/tetcut/live_server.hpp).

#include <tetcut/error.hpp>
#include <tetcut/live_server.hpp>
#include <tetcut/scene.hpp>

#include <fmt/core.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string_view>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

extern const std::string_view kDefaultLiveScene;

void add_serve_command(CLI::App& app, Action& action) {
  struct Options {
    std::filesystem::path scene;
    std::string host = "127.0.0.1";
    int port = 8080;
    std::filesystem::path record;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = app.add_subcommand(
      "serve", "Simulate a scene live and cut it in the browser: prints an address to open (with a token); scalpel, "
               "hook and pin with the mouse. Ctrl-C stops it");
  command->add_option("SCENE", options->scene,
                      "A scene file, as for tetcut sim (default: a femur scanned by CT, from Debian's libcgal-demo, in "
                      "a lattice of 11k tets, held at its base)");
  command->add_option("--host", options->host, "The address to listen on; another than 127.0.0.1 serves other machines");
  command->add_option("--port", options->port, "The port (0: any free one)")->check(CLI::Range(0, 65535));
  command->add_option("--record", options->record, "Write the session's events here on exit: a scene that tetcut sim replays");
  command->callback([options, &action] {
    action = [options] {
      if (!options->record.empty() && options->record.extension() != ".json") {
        throw Error(ErrorKind::kInvalidArgument, "the recording is a scene file: it must end in .json", options->record.string());
      }
      const auto start = Clock::now();
      const Scene scene = options->scene.empty() ? parse_scene(kDefaultLiveScene, "default live scene (examples/live-femur.json)")
                                                 : load_scene(options->scene);
      LiveServerOptions server_options;
      server_options.host = options->host;
      server_options.port = static_cast<std::uint16_t>(options->port);
      server_options.record = options->record;
      LiveServer server(scene, server_options);
      const double seconds = seconds_since(start);
      fmt::print("tetcut serve: {} ready in {:.1f} s\n  open {}\n  (Ctrl-C to stop{})\n",
                 options->scene.empty() ? std::string("the femur") : options->scene.string(), seconds, server.url(),
                 options->record.empty() ? "" : ", writing the recording to " + options->record.string());
      std::fflush(stdout);
      server.run();
      return 0;
    };
  });
}

}  // namespace tetcut::cli
