#include "sim/height_grid.h"
