// A fixture for the Layering.CatchesAnUnprefixedInclude test: a module header
// included without the package name, which the layering check must refuse.
#pragma once
#include "tracks/track.h"
