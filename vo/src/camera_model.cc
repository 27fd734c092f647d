#include "rigcal/vo/camera_model.h"
