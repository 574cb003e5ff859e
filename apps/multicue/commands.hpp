#pragma once
// Subcommands of the multicue command-line tool. Each registers itself on the CLI11 app; the
// callback runs the job and throws multicue exceptions that main() turns into exit codes.

#include <CLI/CLI.hpp>

namespace multicue::cli {

/// Options shared by every subcommand (set on the top-level app).
struct GlobalOptions {
    int threads = 0;  ///< 0 = all cores
};

void AddInfoCommand(CLI::App& app, const GlobalOptions& global);
void AddConvertCommand(CLI::App& app, const GlobalOptions& global);
void AddDownsampleCommand(CLI::App& app, const GlobalOptions& global);
void AddNormalsCommand(CLI::App& app, const GlobalOptions& global);
void AddOutliersCommand(CLI::App& app, const GlobalOptions& global);
void AddPerceiveCommand(CLI::App& app, const GlobalOptions& global);
void AddConfigCommand(CLI::App& app, const GlobalOptions& global);
void AddDemoCommand(CLI::App& app, const GlobalOptions& global);
void AddDbCommand(CLI::App& app, const GlobalOptions& global);
void AddRunCommand(CLI::App& app, const GlobalOptions& global);
void AddSimulateCommand(CLI::App& app, const GlobalOptions& global);
/// `simulate kitchens` (cmd_simulate_kitchens.cpp), attached to the `simulate` command.
void AddSimulateKitchensCommand(CLI::App& simulate, const GlobalOptions& global);
/// `map kitchen` (cmd_map_kitchen.cpp), attached to the `map` command.
void AddMapKitchenCommand(CLI::App& map_command, const GlobalOptions& global);
void AddFeaturesCommand(CLI::App& app, const GlobalOptions& global);
void AddTrainCommand(CLI::App& app, const GlobalOptions& global);
/// `dataset`, `classifier` and `ensemble` (cmd_ml.cpp).
void AddMlCommands(CLI::App& app, const GlobalOptions& global);
void AddMeshCommand(CLI::App& app, const GlobalOptions& global);
/// `dataset extract` (cmd_dataset_extract.cpp); call after AddMlCommands.
void AddDatasetExtractCommand(CLI::App& app, const GlobalOptions& global);
/// `register SOURCE TARGET` (cmd_register.cpp).
void AddRegisterCommand(CLI::App& app, const GlobalOptions& global);
/// `map SCANS... | --manifest M` (cmd_map.cpp). Returns the `map` command so that other map jobs
/// attach subcommands to it (`map kitchen ...`); its own callback skips when one of them ran.
CLI::App* AddMapCommand(CLI::App& app, const GlobalOptions& global);
/// `simulate furniture` (cmd_simulate_furniture.cpp), attached to the `simulate` command.
void AddSimulateFurnitureCommand(CLI::App& simulate, const GlobalOptions& global);
/// `map furniture` (cmd_map_furniture.cpp), attached to the `map` command.
void AddMapFurnitureCommand(CLI::App& map_command, const GlobalOptions& global);
/// `detect furniture` (cmd_map_furniture.cpp): the `detect` command and its furniture job.
void AddDetectFurnitureCommand(CLI::App& app, const GlobalOptions& global);
/// `train furniture` (cmd_map_furniture.cpp), attached to the `train` command.
void AddTrainFurnitureCommand(CLI::App& train_command, const GlobalOptions& global);
void AddTrainFixturesCommand(CLI::App& train_command, const GlobalOptions& global);
/// `train containers` and `train joints` (cmd_train_containers.cpp), attached to the `train`
/// command.
void AddTrainContainersCommand(CLI::App& train_command, const GlobalOptions& global);
void AddTrainJointsCommand(CLI::App& train_command, const GlobalOptions& global);

}  // namespace multicue::cli
