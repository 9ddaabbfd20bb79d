// tetcut view: a web page that shows a result offline in any browser (see include/tetcut/view.hpp).

#include <tetcut/error.hpp>
#include <tetcut/view.hpp>

#include <fmt/core.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"

namespace tetcut::cli {

namespace {

struct ViewOptions {
  fs::path input;
  fs::path out;
  fs::path mesh;
  std::string title;
};

int run_view(const ViewOptions& options) {
  const fs::path& in = options.input;
  if (!fs::exists(in)) throw Error(ErrorKind::kIo, "no such file or directory", in.string());
  const bool directory = fs::is_directory(in);
  fs::path out = options.out;
  if (out.empty()) out = directory ? in / "view.html" : fs::path(in).replace_extension(".html");
  if (out.extension() != ".html") throw Error(ErrorKind::kInvalidArgument, "the page must be a .html file", out.string());
  if (!directory) check_not_input(out, in);
  const auto start = Clock::now();
  const std::vector<view::ViewFrame> frames = view::load_frames(in, options.mesh);
  // The title names what is shown: the file, or the directory ("out/run/" gives "run").
  fs::path named = fs::absolute(in).lexically_normal();
  if (named.filename().empty()) named = named.parent_path();
  const std::string title = !options.title.empty() ? options.title : named.filename().string();
  view::write_page(out, title.empty() ? in.string() : title, frames);
  const bool edges = std::any_of(frames.begin(), frames.end(), [](const view::ViewFrame& f) { return f.mesh_edges.rows() > 0; });
  const bool copies = std::any_of(frames.begin(), frames.end(), [](const view::ViewFrame& f) { return f.mesh_triangles; });
  fmt::print("wrote {} ({} frame{}{}, {:.1f} MB) in {:.2f} s; open it in a browser\n", out.string(), frames.size(),
             frames.size() == 1 ? "" : "s", !edges ? "" : copies ? ", with triangle-copy edges" : ", with tet edges",
             static_cast<double>(fs::file_size(out)) / 1e6, seconds_since(start));
  return 0;
}

}  // namespace

void add_view_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<ViewOptions>();
  CLI::App* command = app.add_subcommand(
      "view", "Write a web page that shows a result in any browser, offline (three.js inlined): orbit, colour by "
              "piece, toggle the embedding tets (or a cloth's triangle copies), step through a simulation's frames");
  command->add_option("IN", options->input,
                      "A directory 'tetcut sim' wrote (its frames, with the edges of its tets or of a cloth's triangle "
                      "copies), a surface (e.g. what 'tetcut cut2d -o' writes), or a tet mesh")
      ->required();
  command->add_option("-o,--out", options->out, "The page to write (default: IN/view.html for a directory, IN.html for a file)");
  command->add_option("--mesh", options->mesh,
                      "A mesh whose edges to show with a surface file: a tet mesh, or a surface such as 'tetcut cut2d "
                      "--copies' writes (the triangle copies)");
  command->add_option("--title", options->title, "The page's title (default: IN's name)");
  command->callback([options, &action] { action = [options] { return run_view(*options); }; });
}

}  // namespace tetcut::cli
