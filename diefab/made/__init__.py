"""How a die is made: materials and fills, the paper net's plan and tabs, labels as regions on faces,
and the mass of the body as made."""
