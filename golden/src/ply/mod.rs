//! Standard 3DGS `.ply` and PlayCanvas/SuperSplat `compressed.ply` reading and writing.
