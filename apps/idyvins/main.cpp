// idyvins: stereo visual-inertial odometry for dynamic scenes (IDY-VINS).

#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>

#include "commands.h"
#include "core/allocator.h"
#include "core/error.h"

int main(int argc, char** argv) {
  using namespace idyvins::app;
  idyvins::configureAllocatorForStreaming();
  CLI::App app{
      "idyvins: stereo visual-inertial odometry for scenes with moving objects.\n"
      "Implements IDY-VINS (inertial motion prior, dynamic landmark elimination and\n"
      "self-adaptive bundle adjustment) on a VINS-Fusion-class estimator.\n"
      "Configs use the VINS-Fusion format; datasets are EuRoC ASL folders.",
      "idyvins"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "idyvins 0.1.0");
  int exit_code = kOk;
  std::string command_line;  // as typed, for run.json (shell-quoted where needed)
  for (int i = 0; i < argc; ++i) command_line += (i ? " " : "") + shellQuote(argv[i]);
  registerInfo(app, exit_code);
  registerSimulate(app, exit_code);
  registerEval(app, exit_code);
  registerTrack(app, exit_code);
  registerRun(app, exit_code, command_line);
  registerReport(app, exit_code);
  registerConvert(app, exit_code);
  registerBench(app, exit_code);
  registerPerturb(app, exit_code);
  std::string names;  // a first word that is no subcommand: say so (CLI11 says "A subcommand is required")
  bool known = argc < 2 || argv[1][0] == '-';
  for (const CLI::App* sub : app.get_subcommands({})) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
    known = known || sub->get_name() == argv[1];
  }
  if (!known) {
    std::fprintf(stderr, "error: unknown command '%s' (expected one of %s; idyvins --help)\n", argv[1], names.c_str());
    return kUsageError;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints the message (and --help / --version their text, exit 0); every usage
    // error exits 2, as docs/cli.md says (CLI11's own codes are 101-120).
    return app.exit(e) == 0 ? kOk : kUsageError;
  } catch (const idyvins::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kInputError;
  } catch (const std::filesystem::filesystem_error& e) {  // a path that cannot be followed: bad input
    std::fprintf(stderr, "error: %s: %s\n", e.path1().string().c_str(), e.code().message().c_str());
    return kInputError;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return kInternalError;
  }
  return exit_code;
}
