// Frames to MP4 or GIF through the ffmpeg program. Spawned directly (no shell), its messages go to
// a log file that becomes part of the error when it fails.

#include <tetcut/error.hpp>
#include <tetcut/render.hpp>

#include <spawn.h>
#include <sys/wait.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace tetcut::render {
namespace {

std::string last_lines(const std::filesystem::path& log, int count) {
  std::ifstream in(log);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  std::string out;
  for (std::size_t i = lines.size() > static_cast<std::size_t>(count) ? lines.size() - count : 0; i < lines.size(); ++i) {
    if (!out.empty()) out.append("; ");
    out.append(lines[i]);
  }
  return out;
}

}  // namespace

void write_animation(const std::filesystem::path& frames, double frames_per_second, const std::filesystem::path& output) {
  const std::string extension = output.extension().string();
  if (extension != ".mp4" && extension != ".gif") {
    throw Error(ErrorKind::kInvalidArgument, "an animation must be .mp4 or .gif", output.string());
  }
  if (!(frames_per_second > 0 && frames_per_second <= 240)) {
    throw Error(ErrorKind::kInvalidArgument, "frames per second must be in (0, 240], not " + std::to_string(frames_per_second));
  }
  // ffmpeg picks the container by extension, so the temporary file keeps it.
  // (Built with append: GCC 12 warns falsely on chains of string operator+.)
  std::string hidden_stem = ".";
  hidden_stem.append(output.stem().string());
  const std::filesystem::path partial = output.parent_path() / (hidden_stem + ".partial").append(extension);
  const std::filesystem::path log = output.parent_path() / (hidden_stem + ".ffmpeg.log");
  std::ostringstream rate;
  rate << frames_per_second;
  std::vector<std::string> args = {"ffmpeg", "-y", "-loglevel", "error", "-framerate", rate.str(), "-start_number", "0",
                                   "-i", frames.string()};
  if (extension == ".mp4") {
    // H.264 in yuv420p needs even sizes; pad by at most one pixel.
    args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                             "-movflags", "+faststart"});
  } else {
    args.insert(args.end(), {"-vf", "split[a][b];[a]palettegen=stats_mode=diff[p];[b][p]paletteuse", "-loop", "0"});
  }
  args.push_back(partial.string());

  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, "ffmpeg", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    std::filesystem::remove(log);
    if (spawned == ENOENT) {
      throw Error(ErrorKind::kUnsupported, "ffmpeg is not installed (Debian package ffmpeg; scripts/install-deps.sh installs it)",
                  output.string());
    }
    throw Error(ErrorKind::kIo, std::string("cannot run ffmpeg: ") + std::strerror(spawned), output.string());
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw Error(ErrorKind::kIo, std::string("waiting for ffmpeg: ") + std::strerror(errno), output.string());
  }
  const std::string messages = last_lines(log, 3);
  std::error_code ignored;
  std::filesystem::remove(log, ignored);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::filesystem::remove(partial, ignored);
    throw Error(ErrorKind::kIo, "ffmpeg failed" + (messages.empty() ? std::string() : ": " + messages), output.string());
  }
  std::filesystem::rename(partial, output);
}

}  // namespace tetcut::render
