// A test helper shared by the point-cloud reader tests (PLY/PCD and LAS): a read that must fail
// with a PointCloudError that names the file.
#pragma once

#include "rowloc/mapping/point_cloud.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace rowloc::test {

/// Expects mapping::ReadPointCloud(path) to throw mapping::PointCloudError whose message names the
/// file and contains `reason`, and whose path() is `path`.
inline void ExpectReadError(const std::filesystem::path& path, const std::string& reason) {
  try {
    mapping::ReadPointCloud(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const mapping::PointCloudError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(path.string()));
    EXPECT_THAT(e.what(), ::testing::HasSubstr(reason));
    EXPECT_EQ(e.path(), path);
  }
}

}  // namespace rowloc::test
