#include "rigcal/drivers/frame.h"
