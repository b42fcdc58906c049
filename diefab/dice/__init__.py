"""What a die is: designs, families, values and how they are read, and the targets they aim at."""
