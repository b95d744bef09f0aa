"""Mutation (Fig. 2): the registry of message mutators and crossover."""
