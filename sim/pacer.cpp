#include "sim/pacer.h"
