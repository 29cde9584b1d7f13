//! Pictures: top-down scene maps with overlays, profile plots.
