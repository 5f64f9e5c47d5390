// Running gnuplot on a plot script without a shell (see report_plots.hpp).
#include "rowloc/sim/report_plots.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <string_view>

namespace rowloc::sim {

std::optional<std::filesystem::path> FindExecutableOnPath(const std::string& name) {
  const char* path_env = std::getenv("PATH");
  if (path_env == nullptr || name.empty() || name.find('/') != std::string::npos) return std::nullopt;
  std::string_view rest(path_env);
  while (true) {
    const std::size_t colon = rest.find(':');
    const std::string_view dir = rest.substr(0, colon);
    const std::filesystem::path candidate = std::filesystem::path(dir.empty() ? "." : std::string(dir)) / name;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (colon == std::string_view::npos) return std::nullopt;
    rest.remove_prefix(colon + 1);
  }
}

GnuplotRun RunGnuplot(const PlotFiles& files) {
  GnuplotRun run;
  const auto gnuplot = FindExecutableOnPath("gnuplot");
  if (!gnuplot) {
    run.message = "gnuplot not found on PATH (install the Debian package gnuplot-nox); the data files and " +
                  (files.directory / files.script).string() + " are written, run `gnuplot " + files.script +
                  "` in " + files.directory.string() + " to draw the plots";
    return run;
  }
  const std::string program = gnuplot->string();
  const std::string dir = files.directory.string();
  const std::string script = files.script;
  const pid_t pid = ::fork();
  if (pid < 0) {
    run.message = "cannot start gnuplot (fork failed)";
    return run;
  }
  if (pid == 0) {  // child: only async-signal-safe calls until exec
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    char* const argv[] = {const_cast<char*>(program.c_str()), const_cast<char*>(script.c_str()), nullptr};
    ::execv(program.c_str(), argv);
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      run.message = "cannot wait for gnuplot";
      return run;
    }
  }
  run.ran = true;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.message = run.exit_code == 0 ? "gnuplot drew the plots in " + dir
                                   : "gnuplot failed with exit status " + std::to_string(run.exit_code) + " on " +
                                         (files.directory / script).string();
  return run;
}

}  // namespace rowloc::sim
