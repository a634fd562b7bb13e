"""What goes over the wire, by resource: request (``*In``) and response (``*Out``) models."""
