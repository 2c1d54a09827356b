"""The provider's one setting (the executable's path) and its icon, shared by the provider and
the algorithms."""

import os

from qgis.core import QgsSettings
from qgis.PyQt.QtGui import QIcon

EXECUTABLE_SETTING = "TOPOSIMP_EXECUTABLE"
ICON_PATH = os.path.join(os.path.dirname(__file__), "icon.svg")

try:  # the Processing plugin's settings page (Settings > Options > Processing > Providers)
    from processing.core.ProcessingConfig import ProcessingConfig, Setting
except ImportError:  # e.g. a QGIS without the Processing plugin: plain settings, same key
    ProcessingConfig = None
    Setting = None


def icon():
    return QIcon(ICON_PATH)


def configured_executable():
    """The executable path set by the user, or '' (then toposimp is looked up on PATH)."""
    if ProcessingConfig is not None:
        value = ProcessingConfig.getSetting(EXECUTABLE_SETTING)
    else:
        value = QgsSettings().value("toposimp/executable", "")
    return (value or "").strip()
