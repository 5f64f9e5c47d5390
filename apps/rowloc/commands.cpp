#include "commands.hpp"

#include "rowloc/mapio/output_file.hpp"

#include <spdlog/spdlog.h>

#include <exception>
#include <filesystem>
#include <new>
#include <stdexcept>
#include <system_error>

namespace rowloc::apps {

void RunReportingInputErrors(std::string_view command, const std::function<void()>& body) {
  int code = kInputErrorExitCode;
  try {
    body();
    return;
  } catch (const std::bad_alloc&) {
    spdlog::error("{}: out of memory", command);
    code = kInternalErrorExitCode;
  } catch (const std::logic_error& e) {
    const bool input = dynamic_cast<const std::invalid_argument*>(&e) || dynamic_cast<const std::domain_error*>(&e) ||
                       dynamic_cast<const std::length_error*>(&e) || dynamic_cast<const std::out_of_range*>(&e);
    spdlog::error("{}: {}{}", command, input ? "" : "internal error: ", e.what());
    if (!input) code = kInternalErrorExitCode;
  } catch (const std::exception& e) {
    spdlog::error("{}: {}", command, e.what());
  }
  throw CLI::RuntimeError(code);
}

void CheckCommandFiles(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs) {
  std::vector<mapio::LabelledPath> in, out;
  for (const NamedPath& i : inputs) {
    if (i.path.empty()) continue;
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(i.path, ec);
    if (status.type() == std::filesystem::file_type::not_found) {
      throw std::invalid_argument(i.label + " '" + i.path + "': no such file");
    }
    if (status.type() == std::filesystem::file_type::directory) {
      throw std::invalid_argument(i.label + " '" + i.path + "': is a directory, expected a file");
    }
    in.push_back({i.label, i.path});
  }
  for (const NamedPath& o : outputs) out.push_back({o.label, o.path});
  try {
    mapio::CheckOutputPaths(in, out);
  } catch (const mapio::OutputFileError& e) {
    throw std::invalid_argument(e.what());
  }
}

void RegisterCommands(CLI::App& app) {
  RegisterExampleCommand(app);
  RegisterMapCommands(app);
  RegisterMapBuildCommands(app);
  RegisterMappingCommands(app);
  RegisterWorldCommand(app);
  RegisterSimulateCommand(app);
  RegisterEvaluateCommand(app);
  RegisterReplayCommand(app);
  RegisterServeCommand(app);
  RegisterSendCommand(app);
  RegisterConfigCommand(app);
  RegisterCalibrateCommand(app);
}

}  // namespace rowloc::apps
