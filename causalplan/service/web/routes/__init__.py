"""The web routes: participant pages and their JSON, research pages, the experiment API, and assets."""
