// SPDX-License-Identifier: Apache-2.0
/// @file commands.h
/// @brief Each sharcbake subcommand registers its options and its action on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>

namespace sharcbake {

void registerRenderCommand(CLI::App& app);
void registerBakeCommand(CLI::App& app);
void registerInfoCommand(CLI::App& app);  ///< `info` and `validate` (info_command.cpp)
void registerCompareCommand(CLI::App& app);
void registerExportVdbCommand(CLI::App& app);  ///< export_vdb_command.cpp
void registerMergeCommand(CLI::App& app);      ///< merge_command.cpp

}  // namespace sharcbake
