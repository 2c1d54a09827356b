"""The toposimp Processing provider: its algorithms and its one setting, the executable's path."""

import os

from qgis.core import QgsProcessingProvider, QgsSettings
from qgis.PyQt.QtGui import QIcon

from .algorithms import CheckAlgorithm, DemAlgorithm, MapAlgorithm, MeshAlgorithm

EXECUTABLE_SETTING = "TOPOSIMP_EXECUTABLE"
_ICON = os.path.join(os.path.dirname(__file__), "icon.svg")

try:  # the Processing plugin's settings page (Settings > Options > Processing > Providers)
    from processing.core.ProcessingConfig import ProcessingConfig, Setting
except ImportError:  # e.g. a QGIS without the Processing plugin: plain settings, same key
    ProcessingConfig = None
    Setting = None


def configured_executable():
    """The executable path set by the user, or '' (then toposimp is looked up on PATH)."""
    if ProcessingConfig is not None:
        value = ProcessingConfig.getSetting(EXECUTABLE_SETTING)
    else:
        value = QgsSettings().value("toposimp/executable", "")
    return (value or "").strip()


class ToposimpProvider(QgsProcessingProvider):
    def id(self):
        return "toposimp"

    def name(self):
        return "toposimp"

    def longName(self):
        return "toposimp: exact, topology-preserving simplification"

    def icon(self):
        return QIcon(_ICON)

    def load(self):
        if ProcessingConfig is not None:
            ProcessingConfig.settingIcons[self.name()] = self.icon()
            ProcessingConfig.addSetting(Setting(
                self.name(), EXECUTABLE_SETTING,
                "toposimp executable (empty: found on PATH)", "", valuetype=Setting.FILE))
            ProcessingConfig.readSettings()
        self.refreshAlgorithms()
        return True

    def unload(self):
        if ProcessingConfig is not None:
            ProcessingConfig.removeSetting(EXECUTABLE_SETTING)

    def loadAlgorithms(self):
        for algorithm in (MapAlgorithm(), CheckAlgorithm(), MeshAlgorithm(), DemAlgorithm()):
            self.addAlgorithm(algorithm)
