//! Reading and writing INRIA `cameras.json` files, and `FILE#i` camera selection.
