#include "cli/commands.h"

int main(int argc, char** argv) { return odotune::cli::run(argc, argv); }
