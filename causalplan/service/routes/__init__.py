"""One module per resource: models, plans, transfers, objects, research, health."""
