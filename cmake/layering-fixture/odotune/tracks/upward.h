// A fixture for the LayeringCatchesUpwardInclude test: tracks/ (a low module)
// including the CLI, which the layering check must refuse.
#pragma once
#include <odotune/tracks/track.h>
#include <odotune/cli/commands.h>
