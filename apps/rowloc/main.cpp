// rowloc: command line of the rowloc localization toolkit. Subcommands are registered by
// functions declared in commands.hpp, one source file each.
#include "commands.hpp"

#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <exception>
#include <new>

int main(int argc, char** argv) {
  // stdout carries results only (reports, summaries, JSON); logs and errors go to stderr.
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
  CLI::App app{"rowloc: map-aided localization between crop rows"};
  app.require_subcommand(1);
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  rowloc::apps::RegisterCommands(app);
  app.parse_complete_callback([&verbose] {
    spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {  // thrown by a command with its status (CLI11 derives it from
    return e.get_exit_code();             // ParseError: caught first, or every status would become 2)
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; any other parse error (unknown option, missing argument, a value
    // out of its range) is bad input: exit 2, not CLI11's own codes (105, 106, ...).
    const int code = app.exit(e);
    return code == 0 ? 0 : rowloc::apps::kInputErrorExitCode;
  } catch (const CLI::Error& e) {
    return app.exit(e);
  } catch (const std::bad_alloc&) {
    spdlog::error("out of memory");
    return rowloc::apps::kInternalErrorExitCode;
  } catch (const std::exception& e) {
    spdlog::error("internal error: {}", e.what());
    return rowloc::apps::kInternalErrorExitCode;
  }
  return 0;
}
