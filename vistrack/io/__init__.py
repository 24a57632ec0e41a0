"""Videos, clips and the files a run reads and writes: decoding and writing video, clip folders and
ground truth, start boxes, clips given as URLs, track CSVs, the toolkits' result files, output
paths and locks, and drawing on frames."""
