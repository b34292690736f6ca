//! Float RGB images, 8-bit quantisation and PNG input/output.
