"""What watches a run (BehaviorTree.CPP calls them loggers): the journal, tick snapshots, MCAP and Foxglove, Groot2 and the web live view."""
