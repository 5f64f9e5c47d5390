// Files chosen by name from a directory (vehicles, maps, filters): a request names a file, never a
// path. A name is 1-64 characters of letters, digits, '-', '_' and '.', not starting with '.'
// (so never "..", "/x" or "a/b"); the file NAME + extension must exist in the directory, and after
// resolving links it must still lie inside the directory (a link leading out of it is refused like
// a path). Whether it is a regular file of a sane size is its reader's check (mapio::ReadInputFile,
// on the opened file): a FIFO or a device in the directory is refused there, naming what it is.
#pragma once

#include "rowloc/service/service_error.hpp"

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace rowloc::service {

/// True for a plain name (see above).
bool IsPlainName(std::string_view name);

/// The file of `name` in `directory` with `extension` (e.g. ".json"). Throws ServiceError:
/// kInvalidName for a name that is not plain or a link leading out of the directory, `missing`
/// (kUnknownVehicle, kUnknownMap or kUnknownFilter) when no such file exists.
std::filesystem::path ResolveNamedFile(const std::filesystem::path& directory, std::string_view name,
                                       std::string_view extension, ErrorCode missing, std::string_view what);

/// The names of the files with `extension` in `directory` that ResolveNamedFile accepts, sorted;
/// empty when the directory does not exist.
std::vector<std::string> ListNamedFiles(const std::filesystem::path& directory, std::string_view extension);

}  // namespace rowloc::service
