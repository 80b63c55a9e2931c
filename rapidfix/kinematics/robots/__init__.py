"""Robot model files (TOML) shipped with rapidfix; one file per robot variant."""
