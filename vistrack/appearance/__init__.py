"""Per-frame feature maps and the appearance cues the model families share: colour histograms against a
ring, grey templates, correlation filters."""
