"""Study sections shared by the Python study tests: small enough to render
in seconds, with every kind of figure and report row."""
import os


def small_lowpoly(scenes, small):
    """A low-poly section: the tessellated sphere at 8 and 16 segments, two
    offsets, the evaluator only. `scenes` is the source tree's scenes/."""
    return {
        'scenes': [os.path.join(scenes, 'lowpoly', 'sphere.json')],
        'set': small,
        'axes': [{'pointer': '/shape/tessellation/segments', 'values': [8, 16]}],
        'convergence': '/shape/tessellation/segments',
        'offsets': ['none', {'id': 'epsilon', 'parameters': {'distance': 0.01}}],
        'renderers': ['evaluator']}
