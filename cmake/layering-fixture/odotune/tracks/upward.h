// A fixture for the LayeringCatchesUpwardInclude test: tracks/ (a low module)
// including the CLI, which the layering check must refuse.
#pragma once
#include "tracks/track.h"
#include "cli/commands.h"
