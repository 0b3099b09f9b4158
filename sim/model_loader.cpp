#include "sim/model_loader.h"
