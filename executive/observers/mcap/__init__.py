"""A run as MCAP: its Foxglove channels, the writer, the recording back end, reading it back and its report."""
