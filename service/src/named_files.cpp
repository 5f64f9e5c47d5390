// Files chosen by name (see named_files.hpp).
#include "rowloc/service/named_files.hpp"

#include <algorithm>

namespace rowloc::service {

bool IsPlainName(std::string_view name) {
  if (name.empty() || name.size() > 64 || name.front() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_' ||
           c == '.';
  });
}

std::filesystem::path ResolveNamedFile(const std::filesystem::path& directory, std::string_view name,
                                       std::string_view extension, ErrorCode missing, std::string_view what) {
  const std::string quoted = std::string(what) + " '" + std::string(name) + "'";
  if (!IsPlainName(name)) {
    throw ServiceError(ErrorCode::kInvalidName,
                       quoted + " is not a plain name (1-64 letters, digits, '-', '_', '.'; not a path)");
  }
  const std::filesystem::path path = directory / (std::string(name) + std::string(extension));
  std::error_code ec;
  // Anything that exists is returned: its reader (mapio::ReadInputFile) refuses what is not a
  // regular file, saying what it is, on the opened file (no window for a swap after this check).
  if (!std::filesystem::exists(path, ec)) {
    throw ServiceError(missing, quoted + ": no file " + std::string(name) + std::string(extension) + " in " +
                                    directory.string());
  }
  const std::filesystem::path real = std::filesystem::canonical(path, ec);
  const std::filesystem::path real_dir = std::filesystem::canonical(directory, ec);
  if (ec || real.parent_path() != real_dir) {
    throw ServiceError(ErrorCode::kInvalidName, quoted + " is a link that leads out of " + directory.string());
  }
  return real;
}

std::vector<std::string> ListNamedFiles(const std::filesystem::path& directory, std::string_view extension) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(directory, ec)) {
    const std::string file = entry.path().filename().string();
    if (file.size() <= extension.size() || !file.ends_with(extension)) continue;
    const std::string name = file.substr(0, file.size() - extension.size());
    try {
      ResolveNamedFile(directory, name, extension, ErrorCode::kInvalidName, "file");
      names.push_back(name);
    } catch (const ServiceError&) {
      // not offered: the same name would be refused when asked for
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace rowloc::service
