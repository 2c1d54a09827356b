"""Registers the provider: at start-up in QGIS (initProcessing) and in qgis_process, which calls
initProcessing on plugins whose metadata says hasProcessingProvider=yes."""

from qgis.core import QgsApplication

from .provider import ToposimpProvider


class ToposimpPlugin:
    def __init__(self, iface):
        self.iface = iface
        self.provider = None

    def initProcessing(self):  # noqa: N802 (QGIS's name)
        if self.provider is None:
            self.provider = ToposimpProvider()
            QgsApplication.processingRegistry().addProvider(self.provider)

    def initGui(self):  # noqa: N802
        self.initProcessing()

    def unload(self):
        if self.provider is not None:
            QgsApplication.processingRegistry().removeProvider(self.provider)
            self.provider = None
