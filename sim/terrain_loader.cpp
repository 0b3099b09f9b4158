#include "sim/terrain_loader.h"
