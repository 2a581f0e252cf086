// A fixture for the LayeringCatchesUpwardInclude test: a downward include.
#pragma once
#include <odotune/tracks/track.h>
