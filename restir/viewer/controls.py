"""The viewer's controls, made from the methods' typed settings (restir/settings.py) rather than
written by hand: one control per `--set` setting of a method, its widget from the default's
type, its tooltip the setting's documentation, marked when it is static (a change compiles other
kernels). The fault injections (`debug.*`) are left out: they make a method biased on purpose,
and the harness refuses them."""
import dataclasses

HIDDEN_PREFIXES = ("debug.",)


@dataclasses.dataclass(frozen=True)
class Control:
    key: str        # the --set key
    widget: str     # "checkbox", "integer", "number" or "text"
    default: object
    doc: str
    static: bool

    @property
    def hint(self) -> str:
        return self.doc + (" (static: a change builds other kernels)" if self.static else "")


def widget_of(default) -> str:
    if isinstance(default, bool):
        return "checkbox"
    if isinstance(default, int):
        return "integer"
    if isinstance(default, float):
        return "number"
    return "text"


def controls_for(integrator_class) -> list[Control]:
    """The controls of a method (an Integrator subclass), in its settings' order."""
    static = set(integrator_class.Settings.static_keys())
    docs = integrator_class.SETTINGS_DOC
    return [Control(key, widget_of(default), default, docs.get(key, ""), key in static)
            for key, default in integrator_class.SETTINGS.items()
            if not key.startswith(HIDDEN_PREFIXES)]
