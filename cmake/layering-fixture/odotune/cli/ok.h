// A fixture for the LayeringCatchesUpwardInclude test: a downward include.
#pragma once
#include "tracks/track.h"
