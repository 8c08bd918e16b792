"""Our own robot descriptions, shipped as package data (``clik.robots``)."""
