//! The float reference renderer, following the published 3DGS rasterizer forward pass.
