"""One module per resource: models, plans, simulations, transfers, objects, research, health."""
