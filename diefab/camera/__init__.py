"""Reading rolls with a camera: marker detection, the die's pose, settled rolls and the roll log."""
