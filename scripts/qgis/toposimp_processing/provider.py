"""The toposimp Processing provider: its algorithms and its one setting, the executable's path."""

from qgis.core import QgsProcessingProvider

from . import settings
from .algorithms import CheckAlgorithm, DemAlgorithm, MapAlgorithm, MeshAlgorithm


class ToposimpProvider(QgsProcessingProvider):
    def id(self):
        return "toposimp"

    def name(self):
        return "toposimp"

    def longName(self):
        return "toposimp: exact, topology-preserving simplification"

    def icon(self):
        return settings.icon()

    def load(self):
        if settings.ProcessingConfig is not None:
            settings.ProcessingConfig.settingIcons[self.name()] = self.icon()
            settings.ProcessingConfig.addSetting(settings.Setting(
                self.name(), settings.EXECUTABLE_SETTING,
                "toposimp executable (empty: found on PATH)", "", valuetype=settings.Setting.FILE))
            settings.ProcessingConfig.readSettings()
        self.refreshAlgorithms()
        return True

    def unload(self):
        if settings.ProcessingConfig is not None:
            settings.ProcessingConfig.removeSetting(settings.EXECUTABLE_SETTING)

    def loadAlgorithms(self):
        for algorithm in (MapAlgorithm(), CheckAlgorithm(), MeshAlgorithm(), DemAlgorithm()):
            self.addAlgorithm(algorithm)
