// A quantized TopoJSON's transform: position (qx, qy) stands for (qx·scale_x + translate_x,
// qy·scale_y + translate_y), each product and sum rounded to double as its clients decode it.
#pragma once

namespace toposimp::io {

struct TopoTransform {
    double scale_x = 1, scale_y = 1, translate_x = 0, translate_y = 0;
};

}  // namespace toposimp::io
