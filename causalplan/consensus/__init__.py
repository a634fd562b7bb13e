"""The crowd's model: one causal model from many participants' models, and synthetic crowds.

``alignment`` puts labels that mean the same (words and the part they sit on) into one node;
``support`` counts who holds each rule; ``build`` makes the consensus model and mapping and
judges them; ``population`` makes synthetic participants with the paper's error kinds;
``curve`` measures the consensus against the mean individual for growing crowds.
"""
