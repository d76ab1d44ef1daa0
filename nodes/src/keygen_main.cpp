// gausstrack-keygen FILE: writes a new random key for a plant and controller pair, readable by
// its owner alone (mode 0600). Give the same file to both with --key; copy it to the other host
// over a channel you trust (scp, a provisioning tool), never over the LCM group.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

#include "gausstrack/nodes/auth.hpp"

int main(int argc, char** argv) {
  std::string path;
  CLI::App app("Writes a new random key for a plant and controller pair (mode 0600); refuses to overwrite a file.");
  app.add_option("FILE", path, "the key file to create")->required();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    gausstrack::nodes::MessageKey::generate(path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  std::printf("gausstrack-keygen: wrote %s (pass it to gausstrack-plant and gausstrack-controller with --key)\n",
              path.c_str());
  return 0;
}
