"""The placement resolver: ``commands.Placement`` -> a world pose, on the lane graph and the map's areas."""
