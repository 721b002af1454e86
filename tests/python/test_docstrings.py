"""Every public name of the spindle package has a docstring: the names
exported, their public methods and properties, and the functions of its
public modules."""
import inspect

import spindle
from spindle import capture, errors, protocol_errors, transform, types


def undocumented():
    missing = []
    seen = set()

    def check(name, obj):
        if id(obj) in seen:
            return
        seen.add(id(obj))
        if not (obj.__doc__ or '').strip():  # a property's: its doc=, else its getter's
            missing.append(name)
        if inspect.isclass(obj):
            for attr, value in vars(obj).items():
                if attr.startswith('_') or not (inspect.isfunction(value) or isinstance(value, (property, classmethod))):
                    continue
                check(f'{name}.{attr}', value.__func__ if isinstance(value, classmethod) else value)

    for module in (spindle, capture, errors, protocol_errors, transform, types):
        check(module.__name__, module)
        for name in getattr(module, '__all__', []):
            obj = getattr(module, name)
            if inspect.isclass(obj) or inspect.isfunction(obj) or inspect.ismodule(obj):
                check(f'{module.__name__}.{name}', obj)
    return missing


def test_every_public_name_has_a_docstring():
    missing = undocumented()
    assert not missing, 'no docstring: ' + ', '.join(missing)
