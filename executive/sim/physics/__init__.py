"""The simulated vehicles' physics, whatever firmware drives them: surface vehicles, aircraft, underwater vehicles."""
