// The shatter command: the CLI11 app, one line per subcommand, and the one place
// where a failure becomes an exit code and an `error:` line (errors.hpp).

#include <CLI/CLI.hpp>

#include <exception>
#include <string>
#include <vector>

#include "shatter/version.hpp"
#include "command.hpp"
#include "errors.hpp"
#include "export.hpp"
#include "fracture.hpp"
#include "info.hpp"
#include "simulate.hpp"
#include "slice.hpp"
#include "validate.hpp"
#include "view.hpp"

int main(int argc, char** argv) {
  using namespace shatter;
  CLI::App app{"shatter: exact plane slicing of closed triangle meshes into breakable objects.\n" +
               cli::exit_codes_help()};
  app.require_subcommand(1);
  app.set_version_flag("--version", "shatter " + std::string(version_string));

  // In the order --help lists them.
  const std::vector<cli::Command> commands = {
      cli::add_validate_command(app),
      cli::add_slice_command(app),
      cli::add_fracture_command(app),
      cli::add_info_command(app),
      cli::add_export_command(app),
      cli::add_simulate_command(app),
      cli::add_view_command(app),
  };

  try {
    app.parse(argc, argv);
    for (const cli::Command& command : commands) {
      if (command.app->parsed()) return command.run();
    }
    throw cli::UsageError("no command given (see --help)");
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (...) {
    return cli::report_failure(cli::failure_of(std::current_exception()));
  }
}
