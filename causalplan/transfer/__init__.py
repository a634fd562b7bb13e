"""Step 3: does a person's causal model transfer to a new object?"""
